// The experiment page: a student's trial (condition, start, finish, give up) and, for tutors, the delay form
// and the class's results as SVG plots (mean total time against delay, with standard errors) and a table.
// It decides nothing: the server assigns conditions, measures runs and refuses what is not allowed.

import { ApiError, fetchJson } from "../js/transport.js";
import { h } from "../js/dom.js";

const root = document.querySelector("#experiment");
const SVG = "http://www.w3.org/2000/svg";

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

async function act(url, after) {
  showError("");
  try {
    const answer = await fetchJson(url, { method: "POST", body: after ?? {} });
    return answer;
  } catch (error) {
    failed(error);
    return null;
  } finally {
    await renderTrial();
  }
}

async function renderTrial() {
  const slot = root.querySelector('[data-slot="trial"]');
  let state;
  try {
    state = await fetchJson("/api/experiment/state");
  } catch (error) {
    failed(error);
    return;
  }
  const { trial, robots } = state;
  if (trial) {
    const console = h("a", { class: "button", href: `/lab/${encodeURIComponent(trial.robot_name)}`, target: "_blank",
      text: "Open the robot's console" });
    const finish = h("button", { type: "button", "data-action": "finish", text: "I have finished the course" });
    const abandon = h("button", { type: "button", class: "button--quiet", "data-action": "abandon", text: "Give up this trial" });
    finish.addEventListener("click", () => act(`/api/experiment/trials/${trial.id}/finish`));
    abandon.addEventListener("click", () => act(`/api/experiment/trials/${trial.id}/abandon`));
    slot.replaceChildren(
      h("p", { text: trial.course === "course-A"
        ? "Drive from A (blue) to B (orange) and back to A, as fast as you can."
        : "Drive from A (blue) to B (orange) between the white lines, as fast as you can. Touching a line sends you back to A." }),
      condition(trial),
      h("p", { class: "experiment__actions" }, console, finish, abandon));
    return;
  }
  if (!robots.length) {
    slot.replaceChildren(h("p", { class: "muted", "data-field": "no-robot",
      text: "No robot runs a course now. Ask your tutor to start one (telelab skill-server --scene course-A)." }));
    return;
  }
  const select = h("select", { name: "robot_name", id: "trial-robot" },
    ...robots.map((robot) => h("option", { value: robot.name, text: `${robot.name} (${robot.scene})` })));
  const start = h("button", { type: "submit", text: "Start a trial" });
  const form = h("form", { class: "experiment__form" }, h("label", {}, "Robot ", select), start);
  form.addEventListener("submit", (event) => {
    event.preventDefault();
    act("/api/experiment/trials", { robot_name: select.value });
  });
  slot.replaceChildren(h("p", { text: "Choose a course robot; the delay and the motion preview are drawn for you." }), form);
}

function svg(tag, attributes = {}, text = "") {
  const node = document.createElementNS(SVG, tag);
  for (const [name, value] of Object.entries(attributes)) node.setAttribute(name, String(value));
  if (text) node.textContent = text;
  return node;
}

/** One course: x = delay (s), y = total time (s); dots are trials, bars are mean ± standard error. */
export function plotCourse(course, trials, summary) {
  const width = 320;
  const height = 220;
  const pad = { left: 44, right: 12, top: 14, bottom: 34 };
  const mine = trials.filter((t) => t.course === course);
  const groups = summary.filter((g) => g.course === course);
  const maxY = Math.max(10, ...mine.map((t) => t.total_time_s), ...groups.map((g) => g.mean_time_s + (g.standard_error_s ?? 0))) * 1.1;
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
  for (const tick of [0, maxY / 2, maxY]) {
    chart.append(svg("text", { class: "plot__label", x: pad.left - 4, y: y(tick) + 4, "text-anchor": "end" }, `${Math.round(tick)}`));
  }
  chart.append(svg("text", { class: "plot__label", x: 10, y: pad.top + 60, transform: `rotate(-90 10 ${pad.top + 60})`, "text-anchor": "middle" }, "total time (s)"));
  for (const trial of mine) {
    chart.append(svg("circle", { class: `plot__point ${trial.feedback ? "plot__on" : "plot__off"}`, r: 3,
      cx: x(trial.delay_s, trial.feedback) + (trial.id % 5) - 2, cy: y(trial.total_time_s) }));
  }
  for (const group of groups) {
    const cls = group.feedback ? "plot__on" : "plot__off";
    const cx = x(group.delay_s, group.feedback);
    const se = group.standard_error_s ?? 0;
    chart.append(svg("path", { class: `plot__err ${cls}`, "data-mean": group.mean_time_s.toFixed(2),
      d: `M${cx - 5},${y(group.mean_time_s + se)}h10M${cx},${y(group.mean_time_s + se)}V${y(group.mean_time_s - se)}M${cx - 5},${y(group.mean_time_s - se)}h10` }));
    chart.append(svg("rect", { class: cls, x: cx - 4, y: y(group.mean_time_s) - 4, width: 8, height: 8 }));
  }
  const legend = h("figcaption", { text: `${course}: squares are means (green: preview on, red: off), bars ± one standard error, dots single trials.` });
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
  renderTrial();
  renderResults();
  bindDelayForm();
}
