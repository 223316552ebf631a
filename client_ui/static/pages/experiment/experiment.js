// The experiment page: a student's trial (condition, the run live as they drive, give up) and, for tutors, the
// delay form and the class's results as SVG plots (mean total time against delay, with standard errors) and a table.
// It decides nothing: the server assigns conditions, measures runs, words the progress and refuses what is not allowed.

import { ApiError, fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";

const root = document.querySelector("#experiment");
const SVG = "http://www.w3.org/2000/svg";
const POLL_MS = 500; // while a trial runs: arrival at A and B and line contacts show within half a second
const RETRY_RECORD_MS = 5000;
const LOG_LENGTH = 8;
const view = { trialId: null, timer: null, recordAfter: 0, message: "", generation: 0 };

function showError(text) {
  const line = root.querySelector("#experiment-error");
  line.textContent = text;
  line.hidden = !text;
}

function failed(error) {
  showError(error instanceof ApiError ? error.message : "The lab server could not be reached.");
}

function condition(trial) {
  const item = (label, value) => h("div", {}, h("dt", { text: label }), h("dd", { text: value }));
  return h("dl", { class: "experiment__condition", "data-field": "condition" },
    item("Course", trial.course), item("Robot", trial.robot_name), item("Video delay", `${trial.delay_s} s`),
    item("Motion preview", trial.feedback ? "on" : "off"));
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
  return course === "course-A" ? ["Start at A", "Reach B", "Back to A"] : ["Start at A", "Reach B"];
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
    target: "_blank", rel: "noopener", text: "Open the robot's console" });
  const abandon = h("button", { type: "button", class: "button button--secondary", "data-action": "abandon",
    text: "Give up this trial" });
  abandon.addEventListener("click", () => act(`/api/experiment/trials/${trial.id}/abandon`));
  const figure = (label, field) => h("div", {}, h("dt", { text: label }), h("dd", { "data-field": field, text: "—" }));
  slot.replaceChildren(
    h("p", { text: trial.course === "course-A"
      ? "Drive from A (blue) to B (orange) and back to A, as fast as you can. The run is recorded when you are back."
      : "Drive from A (blue) to B (orange) between the white lines, as fast as you can. Touching a line sends you " +
        "back to A and the clock keeps running. The run is recorded when you reach B." }),
    condition(trial),
    h("section", { class: "experiment__run", "aria-label": "Your run", "data-field": "run" },
      h("ol", { class: "experiment__steps" }, ...steps),
      h("p", { class: "experiment__message", "data-field": "run-message", role: "status", "aria-live": "polite" }),
      h("dl", { class: "experiment__figures" }, figure("Time", "run-time"), figure("Line contacts", "run-errors")),
      h("ol", { class: "experiment__log", "data-slot": "run-log", "aria-label": "What happened", reversed: true })),
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
  slot.querySelector('[data-field="run-time"]').textContent = run.online ? `${run.time_s.toFixed(1)} s` : "—";
  const errors = slot.querySelector('[data-field="run-errors"]');
  errors.textContent = run.online ? String(run.errors) : "—";
  errors.dataset.count = run.online ? String(run.errors) : "";
  slot.querySelector('[data-field="run-message"]').textContent = run.message;
  if (run.message !== view.message) {
    view.message = run.message;
    const log = slot.querySelector('[data-slot="run-log"]');
    const stamp = new Date().toLocaleTimeString([], { hour: "2-digit", minute: "2-digit", second: "2-digit" });
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
    ? [h("strong", { text: "Trial recorded: " }),
      `${trial.total_time_s.toFixed(1)} s, ${trial.errors} line contact${trial.errors === 1 ? "" : "s"}.`]
    : [h("strong", { text: "Trial given up: " }), "it is not counted. The next trial draws a condition again."];
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
      text: "No robot runs a course now. `telelab up` starts course-a and course-b; if they are missing, " +
        "ask your tutor." }));
    return;
  }
  const select = h("select", { name: "robot_name", id: "trial-robot" },
    ...robots.map((robot) => h("option", {
      value: robot.name, text: `${robot.own ? "Your robot, " : ""}${robot.name} (${robot.scene})` })));
  const start = h("button", { type: "submit", class: "button button--primary",
    text: last?.status === "completed" ? "Start the next trial" : "Start a trial" });
  const course = courseChoice(courses);
  const form = h("form", { class: "experiment__form" }, h("label", {}, "Robot ", select),
    ...(course ? [h("label", {}, "Counts for ", course)] : []), start);
  form.addEventListener("submit", (event) => {
    event.preventDefault();
    act("/api/experiment/trials", { robot_name: select.value, ...(course ? { course_id: Number(course.value) } : {}) });
  });
  slot.replaceChildren(...before,
    h("p", { text: "Choose a course robot; the delay and the motion preview are drawn for you." }), form);
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
    showStart(slot, state);
  }
  if (view.trialId !== null) view.timer = setTimeout(refresh, POLL_MS);
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
  const x = (delay, feedback) => pad.left + ((delay - 0) / 4) * (width - pad.left - pad.right) + (feedback ? -8 : 8);
  const y = (seconds) => height - pad.bottom - (seconds / maxY) * (height - pad.top - pad.bottom);
  const chart = svg("svg", { viewBox: `0 0 ${width} ${height}`, role: "img",
    "aria-label": `${course}: total time against delay, with and without motion preview`, "data-course": course });
  chart.append(svg("line", { class: "plot__axis", x1: pad.left, y1: height - pad.bottom, x2: width - pad.right, y2: height - pad.bottom }));
  chart.append(svg("line", { class: "plot__axis", x1: pad.left, y1: pad.top, x2: pad.left, y2: height - pad.bottom }));
  for (const delay of [1, 3]) {
    chart.append(svg("text", { class: "plot__label", x: x(delay, false) - 8, y: height - pad.bottom + 14, "text-anchor": "middle" }, `${delay} s`));
  }
  chart.append(svg("text", { class: "plot__label", x: width / 2, y: height - 4, "text-anchor": "middle" }, "added video delay"));
  for (let tick = 0; tick <= maxY + step / 2; tick += step) {
    if (tick > 0) chart.append(svg("line", { class: "plot__grid", x1: pad.left, y1: y(tick), x2: width - pad.right, y2: y(tick) }));
    chart.append(svg("text", { class: "plot__label", x: pad.left - 4, y: y(tick) + 4, "text-anchor": "end" }, `${tick}`));
  }
  if (!mine.length) {
    chart.append(svg("text", { class: "plot__empty", x: (pad.left + width - pad.right) / 2, y: height / 2,
      "text-anchor": "middle" }, "no trials yet"));
  }
  chart.append(svg("text", { class: "plot__label", x: 10, y: pad.top + 60, transform: `rotate(-90 10 ${pad.top + 60})`, "text-anchor": "middle" }, "total time (s)"));
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
    chart.append(svg("path", { class: `plot__err ${cls}`, "data-mean": group.mean_time_s.toFixed(2),
      d: `M${cx - 5},${y(group.mean_time_s + se)}h10M${cx},${y(group.mean_time_s + se)}V${y(group.mean_time_s - se)}M${cx - 5},${y(group.mean_time_s - se)}h10` }));
    chart.append(svg("rect", { class: cls, x: cx - 4, y: y(group.mean_time_s) - 4, width: 8, height: 8 }));
  }
  const legend = h("figcaption", { text: `${course}: squares are means (green: preview on, red: off), bars ± one standard error, dots beside them single trials.` });
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
  const head = h("tr", {}, ...["Course", "Delay", "Preview", "Trials", "Mean time", "Std. error", "Mean errors"].map((t) => h("th", { text: t })));
  const rows = data.summary.map((g) => h("tr", {},
    h("td", { text: g.course }), h("td", { text: `${g.delay_s} s` }), h("td", { text: g.feedback ? "on" : "off" }),
    h("td", { text: String(g.n) }), h("td", { text: `${g.mean_time_s.toFixed(1)} s` }),
    h("td", { text: g.standard_error_s === null ? "—" : `${g.standard_error_s.toFixed(1)} s` }),
    h("td", { text: g.mean_errors.toFixed(2) })));
  table.replaceChildren(h("thead", {}, head), h("tbody", {}, ...(rows.length ? rows : [h("tr", {}, h("td", { colspan: 7, text: "No completed trials yet." }))])));
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
      result.textContent = `${answer.username}: ${answer.delay_s} s added to video and telemetry.`;
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
  bindDelayForm();
}
