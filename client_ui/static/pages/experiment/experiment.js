// The experiment page: a student's trial (condition, the run live as they drive, give up) and, for tutors, the
// delay form and the class's results as SVG plots (mean total time against delay, with standard errors) and a table.
// It decides nothing: the server assigns conditions, measures runs, words the progress and refuses what is not allowed.

import { ApiError, fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { DATE_LOCALE, fixed, t } from "../../lib/i18n.js";

const root = document.querySelector("#experiment");
const SVG = "http://www.w3.org/2000/svg";
const POLL_MS = 500; // while a trial runs: arrival at A and B and line contacts show within half a second
const LEARNING_POLL_MS = 1000; // the learning period's countdown
const RETRY_RECORD_MS = 5000;
const LOG_LENGTH = 8;
const view = { trialId: null, timer: null, recordAfter: 0, message: "", generation: 0, learning: false };

function showError(text) {
  const line = root.querySelector("#experiment-error");
  line.textContent = text;
  line.hidden = !text;
}

function failed(error) {
  showError(error instanceof ApiError ? error.message : t("The lab server could not be reached."));
}

function condition(trial) {
  const item = (label, value) => h("div", {}, h("dt", { text: label }), h("dd", { text: value }));
  return h("dl", { class: "experiment__condition", "data-field": "condition" },
    item(t("Course"), trial.course), item(t("Robot"), trial.robot_name), item(t("Video delay"), trial.delay_s === 0 ? t("none (control)") : `${trial.delay_s} s`),
    item(t("Motion preview"), trial.feedback ? t("on") : t("off")),
    ...(trial.commands_delayed ? [item(t("Commands"), t("delayed too"))] : []));
}

async function act(url, body) {
  showError("");
  try {
    return await fetchJson(url, { method: "POST", body: body ?? {} });
  } catch (error) {
    failed(error);
    return null;
  } finally {
    await refresh();
  }
}

/** The course's stops in order; the run's phase says which are behind the robot. */
function courseSteps(course) {
  return course === "course-A" ? [t("Start at A"), t("Reach B"), t("Back to A")] : [t("Start at A"), t("Reach B")];
}

function reachedSteps(run) {
  if (!run?.online) return 0;
  if (run.finished) return Infinity;
  return { to_b: 1, to_a: 2 }[run.phase] ?? 0;
}

function buildTrial(slot, trial) {
  const steps = courseSteps(trial.course).map((label, index) =>
    h("li", { class: "experiment__step", "data-step": String(index) }, label));
  const robotConsole = h("a", { class: "button button--primary", href: `/lab/${encodeURIComponent(trial.robot_name)}`,
    target: "_blank", rel: "noopener", text: t("Open the robot's console") });
  const abandon = h("button", { type: "button", class: "button button--secondary", "data-action": "abandon",
    text: t("Give up this trial") });
  abandon.addEventListener("click", () => act(`/api/experiment/trials/${trial.id}/abandon`));
  const figure = (label, field) => h("div", {}, h("dt", { text: label }), h("dd", { "data-field": field, text: "—" }));
  slot.replaceChildren(
    h("p", { text: trial.course === "course-A"
      ? t("Drive from A (blue) to B (orange) and back to A, as fast as you can. The run is recorded when you are back.")
      : t("Drive from A (blue) to B (orange) between the white lines, as fast as you can. Touching a line sends you back to A and the clock keeps running. The run is recorded when you reach B.") }),
    condition(trial),
    h("section", { class: "experiment__run", "aria-label": t("Your run"), "data-field": "run" },
      h("ol", { class: "experiment__steps" }, ...steps),
      h("p", { class: "experiment__message", "data-field": "run-message", role: "status", "aria-live": "polite" }),
      h("dl", { class: "experiment__figures" }, figure(t("Time"), "run-time"), figure(t("Line contacts"), "run-errors")),
      h("ol", { class: "experiment__log", "data-slot": "run-log", "aria-label": t("What happened"), reversed: true })),
    h("p", { class: "experiment__actions" }, robotConsole, abandon));
  view.trialId = trial.id;
  view.message = "";
}

function updateRun(slot, trial, run) {
  const reached = reachedSteps(run);
  for (const step of slot.querySelectorAll(".experiment__step")) {
    const index = Number(step.dataset.step);
    step.dataset.state = index < reached ? "done" : index === reached ? "current" : "todo";
  }
  const section = slot.querySelector('[data-field="run"]');
  section.dataset.phase = run.online ? (run.finished ? "finished" : run.phase) : "offline";
  slot.querySelector('[data-field="run-time"]').textContent = run.online ? `${fixed(run.time_s, 1)} s` : "—";
  const errors = slot.querySelector('[data-field="run-errors"]');
  errors.textContent = run.online ? String(run.errors) : "—";
  errors.dataset.count = run.online ? String(run.errors) : "";
  slot.querySelector('[data-field="run-message"]').textContent = run.message;
  if (run.message !== view.message) {
    view.message = run.message;
    const log = slot.querySelector('[data-slot="run-log"]');
    const stamp = new Date().toLocaleTimeString(DATE_LOCALE, { hour: "2-digit", minute: "2-digit", second: "2-digit" });
    log.prepend(h("li", {}, h("time", { text: stamp }), ` ${run.message}`));
    while (log.children.length > LOG_LENGTH) log.lastElementChild.remove();
  }
  // The robot saw the course finished after the trial began: record it (the server checks again).
  if (run.finished && Date.now() >= view.recordAfter) {
    view.recordAfter = Date.now() + RETRY_RECORD_MS;
    act(`/api/experiment/trials/${trial.id}/finish`);
  }
}

/** The student's last trial as it ended: recorded with its time, or given up and not counted. */
function lastTrial(trial) {
  const outcome = trial.status === "completed"
    ? [h("strong", { text: t("Trial recorded: ") }),
      (trial.errors === 1 ? t("{total_time_s} s, 1 line contact.", { total_time_s: fixed(trial.total_time_s) })
        : t("{total_time_s} s, {errors} line contacts.", { total_time_s: fixed(trial.total_time_s), errors: trial.errors }))]
    : [h("strong", { text: t("Trial given up: ") }), t("it is not counted. The next trial runs the same condition again.")];
  return h("div", { class: `experiment__recorded experiment__recorded--${trial.status}`, "data-field": "last-trial",
    "data-status": trial.status }, h("p", {}, ...outcome), condition(trial));
}

/** The courses a trial may count for: none or one needs no choice; several, a select. */
function courseChoice(courses) {
  if (courses.length < 2) return null;
  return h("select", { name: "course_id", id: "trial-course" },
    ...courses.map((course) => h("option", { value: String(course.id), text: `${course.code} — ${course.title}` })));
}

function showStart(slot, state) {
  view.trialId = null;
  const { robots, last_trial: last, courses = [] } = state;
  const before = last ? [lastTrial(last)] : [];
  if (!robots.length) {
    slot.replaceChildren(...before, h("p", { class: "muted", "data-field": "no-robot",
      text: t("No robot runs a course now. `telelab up` starts course-a and course-b; if they are missing, ask your tutor.") }));
    return;
  }
  const select = h("select", { name: "robot_name", id: "trial-robot" },
    ...robots.map((robot) => h("option", {
      value: robot.name, text: robot.own ? t("Your robot, {name} ({scene})", { name: robot.name, scene: robot.scene })
        : `${robot.name} (${robot.scene})` })));
  const start = h("button", { type: "submit", class: "button button--primary",
    text: last?.status === "completed" ? t("Start the next trial") : t("Start a trial") });
  const course = courseChoice(courses);
  const form = h("form", { class: "experiment__form" }, h("label", {}, t("Robot "), select),
    ...(course ? [h("label", {}, t("Counts for "), course)] : []), start);
  form.addEventListener("submit", (event) => {
    event.preventDefault();
    act("/api/experiment/trials", { robot_name: select.value, ...(course ? { course_id: Number(course.value) } : {}) });
  });
  slot.replaceChildren(...before,
    h("p", { text: t("Choose a course robot; the delay and the motion preview come in the order the study set for you.") }), form);
}

const EXPERIENCE = [["", "—"], ["none", t("None")], ["some", t("Some")], ["much", t("Much")]];

function choiceField(label, name, options) {
  return h("label", {}, label, h("select", { name },
    ...options.map(([value, text]) => h("option", { value, text: t(text) }))));
}

/** Asked once before the first trial, as the thesis' participant table: kept only with consent. */
function detailsForm(slot) {
  const consent = h("input", { type: "checkbox", name: "consent" });
  const form = h("form", { class: "experiment__form experiment__details", "data-field": "details" },
    h("p", { class: "experiment__wide", text: t("Before your first trial: a few details about you, as the study reports them. They are kept only if you agree, your tutor sees them for the class as a whole, and they leave the lab in an export only if your tutor enables it.") }),
    h("label", {}, t("Age"), h("input", { type: "number", name: "age", min: "10", max: "120", step: "1", inputmode: "numeric" })),
    choiceField(t("Where you drive from"), "location", [["", "—"], ["lab", t("In the lab")], ["remote", t("Remote")]]),
    choiceField(t("Experience with video games"), "games_experience", EXPERIENCE),
    choiceField(t("Experience with robots"), "robots_experience", EXPERIENCE),
    h("label", { class: "experiment__consent" }, consent, t("I agree that these details are kept for the study.")),
    h("p", { class: "experiment__actions experiment__wide" },
      h("button", { type: "submit", class: "button button--primary", text: t("Save and continue") }),
      h("button", { type: "button", class: "button button--secondary", "data-action": "decline",
        text: t("Continue without giving details") })));
  const send = (agreed) => {
    const body = { consent: agreed };
    if (agreed) {
      const age = form.elements.age.value.trim();
      if (age) body.age = Number(age);
      for (const name of ["location", "games_experience", "robots_experience"]) {
        if (form.elements[name].value) body[name] = form.elements[name].value;
      }
    }
    return put("/api/experiment/participant", body);
  };
  form.addEventListener("submit", (event) => {
    event.preventDefault();
    send(consent.checked);
  });
  form.querySelector('[data-action="decline"]').addEventListener("click", () => send(false));
  slot.replaceChildren(form);
}

async function put(url, body) {
  showError("");
  try {
    return await fetchJson(url, { method: "PUT", body });
  } catch (error) {
    failed(error);
    return null;
  } finally {
    await refresh();
  }
}

function minutes(seconds) {
  const whole = Math.max(0, Math.ceil(seconds));
  return `${Math.floor(whole / 60)}:${String(whole % 60).padStart(2, "0")}`;
}

/** The learning period: time to drive the course freely (no delay) before the first trial. */
function learningPeriod(slot, protocol, robots) {
  const robotLinks = robots.map((robot) => h("a", { class: "button button--secondary",
    href: `/lab/${encodeURIComponent(robot.name)}`, target: "_blank", rel: "noopener",
    text: t("Open {name}'s console", { name: robot.name }) }));
  if (!protocol.learning_started) {
    const start = h("button", { type: "button", class: "button button--primary", text: t("Start the learning period") });
    start.addEventListener("click", () => act("/api/experiment/learning"));
    slot.replaceChildren(h("div", { "data-field": "learning", "data-state": "ready" },
      h("p", { text: t("First, a learning period: {minutes} min to drive a course robot freely, without any delay, and learn how it handles. Your trials begin after it.", { minutes: minutes(protocol.learning_s) }) }),
      h("p", { class: "experiment__actions" }, start, ...robotLinks)));
    return;
  }
  slot.replaceChildren(h("div", { "data-field": "learning", "data-state": "running" },
    h("p", { class: "experiment__message", role: "status", "aria-live": "polite" },
      t("Learning period: {left} left. Drive the course freely; the trials begin after it.", { left: minutes(protocol.learning_left_s) })),
    h("p", { class: "experiment__actions" }, ...robotLinks)));
}

/** Before a trial: the details (once), the learning period, then the choice of robot. */
function showBeforeTrial(slot, state) {
  const protocol = state.protocol;
  view.learning = false;
  view.trialId = null;
  if (protocol && !protocol.details_answered) {
    detailsForm(slot);
  } else if (protocol && !protocol.learning_done) {
    view.learning = protocol.learning_started;
    learningPeriod(slot, protocol, state.robots ?? []);
  } else {
    showStart(slot, state);
  }
}

/** Reads the state once and shows it; while a trial runs, reads it again every POLL_MS. */
async function refresh() {
  const generation = ++view.generation;
  clearTimeout(view.timer);
  const slot = root.querySelector('[data-slot="trial"]');
  let state = null;
  try {
    state = await fetchJson("/api/experiment/state");
  } catch (error) {
    failed(error);
  }
  if (generation !== view.generation) return; // a newer read started meanwhile: it shows the state and polls on
  if (state?.trial) {
    if (view.trialId !== state.trial.id) buildTrial(slot, state.trial);
    updateRun(slot, state.trial, state.run);
  } else if (state) {
    showBeforeTrial(slot, state);
  }
  if (view.trialId !== null) view.timer = setTimeout(refresh, POLL_MS);
  else if (view.learning) view.timer = setTimeout(refresh, LEARNING_POLL_MS);
}

function svg(tag, attributes = {}, text = "") {
  const node = document.createElementNS(SVG, tag);
  for (const [name, value] of Object.entries(attributes)) node.setAttribute(name, String(value));
  if (text) node.textContent = text;
  return node;
}

/** A round axis step (1, 2 or 5 times a power of ten) near `rough` seconds. */
function niceStep(rough) {
  const power = 10 ** Math.floor(Math.log10(rough));
  return [1, 2, 5, 10].map((m) => m * power).find((candidate) => candidate >= rough);
}

/** One course: x = delay (s), y = total time (s); dots are trials, bars are mean ± standard error. */
export function plotCourse(course, trials, summary) {
  const width = 320;
  const height = 220;
  const pad = { left: 44, right: 12, top: 14, bottom: 34 };
  const mine = trials.filter((t) => t.course === course);
  const groups = summary.filter((g) => g.course === course);
  const highest = Math.max(10, ...mine.map((t) => t.total_time_s), ...groups.map((g) => g.mean_time_s + (g.standard_error_s ?? 0)));
  const step = niceStep(highest / 4);
  const maxY = Math.ceil((highest * 1.05) / step) * step;
  // The no-delay control sits half a second right of the axis, the delays at their seconds beyond it.
  const x = (delay, feedback) => pad.left + ((delay + 0.5) / 4) * (width - pad.left - pad.right) + (feedback ? -8 : 8);
  const y = (seconds) => height - pad.bottom - (seconds / maxY) * (height - pad.top - pad.bottom);
  const chart = svg("svg", { viewBox: `0 0 ${width} ${height}`, role: "img",
    "aria-label": t("{course}: total time against delay, with and without motion preview", { course }), "data-course": course });
  chart.append(svg("line", { class: "plot__axis", x1: pad.left, y1: height - pad.bottom, x2: width - pad.right, y2: height - pad.bottom }));
  chart.append(svg("line", { class: "plot__axis", x1: pad.left, y1: pad.top, x2: pad.left, y2: height - pad.bottom }));
  for (const delay of [0, 1, 3]) {
    chart.append(svg("text", { class: "plot__label", x: x(delay, false) - 8, y: height - pad.bottom + 14, "text-anchor": "middle" }, `${delay} s`));
  }
  chart.append(svg("text", { class: "plot__label", x: width / 2, y: height - 4, "text-anchor": "middle" }, t("added video delay")));
  for (let tick = 0; tick <= maxY + step / 2; tick += step) {
    if (tick > 0) chart.append(svg("line", { class: "plot__grid", x1: pad.left, y1: y(tick), x2: width - pad.right, y2: y(tick) }));
    chart.append(svg("text", { class: "plot__label", x: pad.left - 4, y: y(tick) + 4, "text-anchor": "end" }, `${tick}`));
  }
  if (!mine.length) {
    chart.append(svg("text", { class: "plot__empty", x: (pad.left + width - pad.right) / 2, y: height / 2,
      "text-anchor": "middle" }, t("no trials yet")));
  }
  chart.append(svg("text", { class: "plot__label", x: 10, y: pad.top + 60, transform: `rotate(-90 10 ${pad.top + 60})`, "text-anchor": "middle" }, t("total time (s)")));
  for (const trial of mine) {
    chart.append(svg("circle", { class: `plot__point ${trial.feedback ? "plot__on" : "plot__off"}`, r: 3,
      // Beside the mean's bar on its outer side (preview on left, off right), never behind a square.
      cx: x(trial.delay_s, trial.feedback) + (trial.feedback ? -1 : 1) * (10 + (trial.id % 5)),
      cy: y(trial.total_time_s) }));
  }
  for (const group of groups) {
    const cls = group.feedback ? "plot__on" : "plot__off";
    const cx = x(group.delay_s, group.feedback);
    const se = group.standard_error_s ?? 0;
    chart.append(svg("path", { class: `plot__err ${cls}`, "data-mean": group.mean_time_s.toFixed(2), // data, not text: a data attribute
      d: `M${cx - 5},${y(group.mean_time_s + se)}h10M${cx},${y(group.mean_time_s + se)}V${y(group.mean_time_s - se)}M${cx - 5},${y(group.mean_time_s - se)}h10` }));
    chart.append(svg("rect", { class: cls, x: cx - 4, y: y(group.mean_time_s) - 4, width: 8, height: 8 }));
  }
  const legend = h("figcaption", { text: t("{course}: squares are means (green: preview on, red: off), bars ± one standard error, dots beside them single trials.", { course }) });
  return h("figure", {}, chart, legend);
}

async function renderResults() {
  const plots = root.querySelector('[data-slot="plots"]');
  if (!plots) return;
  let data;
  try {
    data = await fetchJson("/api/experiment/results");
  } catch (error) {
    failed(error);
    return;
  }
  plots.replaceChildren(...["course-A", "course-B"].map((course) => plotCourse(course, data.trials, data.summary)));
  const table = root.querySelector('[data-slot="summary"]');
  const head = h("tr", {}, ...[t("Course"), t("Delay"), t("Preview"), t("Trials"), t("Mean time"), t("Std. error"), t("Mean errors")].map((label) => h("th", { text: label })));
  const rows = data.summary.map((g) => h("tr", {},
    h("td", { text: g.course }), h("td", { text: `${g.delay_s} s` }), h("td", { text: g.feedback ? t("on") : t("off") }),
    h("td", { text: String(g.n) }), h("td", { text: `${fixed(g.mean_time_s, 1)} s` }),
    h("td", { text: g.standard_error_s === null ? "—" : `${fixed(g.standard_error_s, 1)} s` }),
    h("td", { text: fixed(g.mean_errors, 2) })));
  table.replaceChildren(h("thead", {}, head), h("tbody", {}, ...(rows.length ? rows : [h("tr", {}, h("td", { colspan: 7, text: t("No completed trials yet.") }))])));
  renderComparisons(root.querySelector('[data-slot="comparisons"]'), data.comparisons);
  renderParticipants(root.querySelector('[data-slot="participants"]'), data.participants, data.orders);
}

function percent(share) {
  return share === null ? "—" : `${fixed(share * 100, 0)} %`;
}

/** What the thesis reports per course and delay: the time the preview saves, and each mean against the control. */
function renderComparisons(table, comparisons) {
  const head = h("tr", {}, ...[t("Course"), t("Delay"), t("Preview saves"), t("Preview on vs control"),
    t("Preview off vs control")].map((text) => h("th", { text })));
  const ratio = (value) => (value === null ? "—" : `× ${fixed(value, 2)}`);
  const rows = comparisons.map((c) => h("tr", { "data-course": c.course, "data-delay": String(c.delay_s) },
    h("td", { text: c.course }), h("td", { text: `${c.delay_s} s` }),
    h("td", { "data-field": "saves", text: percent(c.preview_saves) }),
    h("td", { text: ratio(c.on_vs_control) }), h("td", { text: ratio(c.off_vs_control) })));
  table.replaceChildren(
    h("caption", { text: t("Compared: less time with the preview, and each mean as a multiple of the no-delay control's") }),
    h("thead", {}, head),
    h("tbody", {}, ...(rows.length ? rows : [h("tr", {}, h("td", { colspan: 5, text: t("No completed trials yet.") }))])));
}

/** The class's participants as the thesis' table: consenting ones' ages and experience, and the orders in use. */
function renderParticipants(slot, people, orders) {
  const counts = (map, keys) => keys.map((key) => `${t(key)} ${map[key] ?? 0}`).join(", ");
  const experience = ["none", "some", "much"];
  const ages = people.age_mean === null ? "—"
    : t("{min}-{max}, mean {mean}", { min: people.age_min, max: people.age_max, mean: fixed(people.age_mean, 1) });
  const item = (label, value, field) => h("div", {}, h("dt", { text: label }), h("dd", { "data-field": field, text: value }));
  const used = people.orders_in_use.filter((n) => n > 0).length;
  slot.replaceChildren(h("dl", { class: "experiment__condition" },
    item(t("Participants"), t("{n} ({consenting} gave details)", { n: people.participants, consenting: people.consenting }),
      "participants"),
    item(t("Ages"), ages, "ages"),
    item(t("Drove from"), counts(people.location, ["lab", "remote"]), "location"),
    item(t("Video games"), counts(people.games_experience, experience), "games"),
    item(t("Robots"), counts(people.robots_experience, experience), "robots"),
    item(t("Orders in use"), t("{used} of {orders} rows: {counts}", { used, orders, counts: people.orders_in_use.join(" ") }),
      "orders")));
}

/** A tutor's protocol per course they teach: the learning period and the two switches. */
async function renderProtocols() {
  const slot = root.querySelector('[data-slot="protocols"]');
  if (!slot) return;
  let data;
  try {
    data = await fetchJson("/api/experiment/protocols");
  } catch (error) {
    failed(error);
    return;
  }
  if (!data.courses.length) {
    slot.replaceChildren(h("p", { class: "muted",
      text: t("You teach no course yet: students of no course get the defaults (5 min learning period).") }));
    return;
  }
  slot.replaceChildren(...data.courses.map((course) => {
    const learning = h("input", { type: "number", name: "learning_min", min: "0", max: "60", step: "any",
      value: String(course.learning_s / 60) });
    const delayCommands = h("input", { type: "checkbox", name: "delay_commands" });
    delayCommands.checked = course.delay_commands;
    const exportDetails = h("input", { type: "checkbox", name: "export_participants" });
    exportDetails.checked = course.export_participants;
    const result = h("span", { role: "status", "data-field": "protocol-result" });
    const form = h("form", { class: "experiment__form", "data-course": course.code },
      h("strong", { class: "experiment__wide", text: `${course.code} — ${course.title}` }),
      h("label", {}, t("Learning period (min)"), learning),
      h("label", { class: "experiment__consent" }, delayCommands, t("Delay the commands too (a distant proxy)")),
      h("label", { class: "experiment__consent" }, exportDetails, t("Put consenting participants' details in the CSV")),
      h("button", { type: "submit", class: "button button--primary", text: t("Save protocol") }), result);
    form.addEventListener("submit", async (event) => {
      event.preventDefault();
      result.textContent = "";
      try {
        const saved = await fetchJson(`/api/experiment/protocols/${course.id}`, { method: "PUT", body: {
          learning_s: Math.round(Number(learning.value) * 60), delay_commands: delayCommands.checked,
          export_participants: exportDetails.checked } });
        result.textContent = t("Saved: {minutes} min learning period.", { minutes: fixed(saved.learning_s / 60, 1) });
        showError("");
      } catch (error) {
        failed(error);
      }
    });
    return form;
  }));
}

function bindDelayForm() {
  const form = root.querySelector("#delay-form");
  if (!form) return;
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const result = form.querySelector('[data-field="delay-result"]');
    const username = form.elements.username.value.trim();
    try {
      const answer = await fetchJson(`/api/experiment/delays/${encodeURIComponent(username)}`, {
        method: "PUT", body: { delay_s: Number(form.elements.delay_s.value) } });
      result.textContent = t("{username}: {delay_s} s added to video and telemetry.", { username: answer.username, delay_s: answer.delay_s });
      showError("");
    } catch (error) {
      result.textContent = "";
      failed(error);
    }
  });
}

if (root) {
  refresh();
  renderResults();
  renderProtocols();
  bindDelayForm();
}
