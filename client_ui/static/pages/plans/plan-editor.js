// The plan editor: write and check a plan (errors marked on their lines), save it as a version, copy, share,
// export; predict it (a fast simulated copy of the lab robot, its trace streamed as it grows) and run it on a lab
// robot during one's turn, each trace drawn on the map with its line progress and its end state.
import { Channel, fetchJson, fetchJsonLines, parseJsonMessage } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { boxCorners, fitView, sceneBounds, worldToCanvas } from "../../lib/map-geometry.js";
import { addSample, endErrorCm, endStateWords, isFinal, lineOf } from "./plan-trace.js";
import { fixed, t } from "../../lib/i18n.js";

const root = document.getElementById("plan-editor");
const planId = Number(root.dataset.planId);
const mine = root.dataset.mine === "true";
const text = root.querySelector("textarea[name=text]");
const gutter = root.querySelector("[data-slot=gutter]");
const errorList = root.querySelector("[data-slot=errors]");
const checkStatus = root.querySelector("[data-field=check-status]");
const versionSelect = root.querySelector("[data-field=version]");
const nameInput = root.querySelector("input[name=name]");
const robotSelect = root.querySelector("[data-field=robot]");
const turnLine = root.querySelector("[data-field=turn]");
const startLine = root.querySelector("[data-field=start]");
const startRobotName = root.querySelector("[data-field=start-robot]");
const progressLine = root.querySelector("[data-field=progress]");
const endStateLine = root.querySelector("[data-field=end-state]");
const endErrorLine = root.querySelector("[data-field=end-error]");
const canvas = root.querySelector("[data-field=map]");
const button = (action) => root.querySelector(`[data-action=${action}]`);
const TRACE_COLOURS = { predicted: "#1d6fd8", real: "#e07b00" };

const state = { errors: [], runningLine: null, latest: 0, sceneBoxes: [], traces: { predicted: [], real: [] },
  run: null, queue: null };

// --- text, gutter and errors -------------------------------------------------------------------

function renderGutter() {
  const count = text.value.split("\n").length;
  const errorLines = new Set(state.errors.map((e) => e.line));
  const lines = [];
  for (let line = 1; line <= count; line += 1) {
    const mark = line === state.runningLine ? "▶" : errorLines.has(line) ? "⚠" : " ";
    const classes = ["plan-code__line"];
    if (errorLines.has(line)) classes.push("plan-code__line--error");
    if (line === state.runningLine) classes.push("plan-code__line--running");
    lines.push(h("span", { class: classes.join(" "), "data-line": line }, `${mark}${String(line).padStart(3)}`));
    lines.push("\n");
  }
  gutter.replaceChildren(...lines);
  gutter.scrollTop = text.scrollTop;
}

function moveToLine(line, column = 1) {
  const starts = [0];
  for (let i = 0; i < text.value.length; i += 1) if (text.value[i] === "\n") starts.push(i + 1);
  const at = (starts[line - 1] ?? 0) + Math.max(0, column - 1);
  text.focus();
  text.setSelectionRange(at, at);
}

function showErrors(errors) {
  state.errors = errors;
  errorList.replaceChildren(...errors.map((error) => h("li", { class: "plans-errors__item", "data-line": error.line },
    h("button", { type: "button", class: "plans-errors__goto", onclick: () => moveToLine(error.line, error.column) },
      error.line ? t("Line {line}, column {column}", { line: error.line, column: error.column }) : t("The plan")),
    ` ${error.message}`)));
  renderGutter();
}

function summaryWords(summary) {
  if (!summary) return "";
  const duration = summary.max_duration_s == null ? t("no time bound") : t("at most {max_duration_s} s", { max_duration_s: summary.max_duration_s });
  return (summary.steps === 1 ? t("1 step, {duration}", { duration }) : t("{steps} steps, {duration}", { steps: summary.steps, duration }));
}

async function check() {
  checkStatus.textContent = t("Checking…");
  try {
    const answer = await fetchJson("/api/plans/check", { method: "POST", body: { text: text.value } });
    showErrors(answer.errors);
    checkStatus.textContent = answer.valid
      ? t("The plan is valid: {summary}.", { summary: summaryWords(answer.summary) })
      : (answer.errors.length === 1 ? t("1 problem found: see the marked lines.")
        : t("{length} problems found: see the marked lines.", { length: answer.errors.length }));
    checkStatus.dataset.valid = String(answer.valid);
    return answer.valid;
  } catch (error) {
    checkStatus.textContent = error.message;
    checkStatus.dataset.valid = "false";
    return false;
  }
}

// --- the stored plan ---------------------------------------------------------------------------

function showPlan(plan) {
  text.value = plan.text;
  // Read-only until the stored text is in: what a person typed before would be overwritten.
  text.readOnly = text.dataset.editable !== "true";
  text.removeAttribute("aria-busy");
  state.latest = plan.latest_version;
  state.saved = { text: plan.text, version: plan.version };
  versionSelect.replaceChildren(...plan.versions.map((v) => h("option", { value: v.version,
    selected: v.version === plan.version }, v.version === plan.latest_version ? t("{version} (latest)", { version: v.version }) : String(v.version))));
  const shared = plan.shared_with ? t("Shared with {code}.", { code: plan.shared_with.code }) : t("Not shared.");
  root.closest("main").querySelector("[data-field=plan-about]").textContent = plan.mine
    ? t("Your plan, version {version} of {latest_version}. {shared}", { version: plan.version, latest_version: plan.latest_version, shared })
    : t("{owner}'s plan, shared with you to read and run: copy it to change it. Version {version}.", { owner: plan.owner, version: plan.version });
  root.closest("main").querySelector("[data-field=plan-name]").textContent = plan.name;
  const skillBox = root.querySelector("input[name=console_skill]");
  if (skillBox) skillBox.checked = Boolean(plan.console_skill);
  const shareSelect = root.querySelector("[data-field=share-course]");
  if (shareSelect) {
    // Disabled until the stored sharing is in, as the text is: a course chosen before would be reset.
    shareSelect.value = plan.shared_with ? String(plan.shared_with.id) : "";
    shareSelect.disabled = false;
    button("share").disabled = false;
  }
  showErrors([]);
}

async function load(version = null) {
  const query = version ? `?version=${version}` : "";
  try {
    showPlan((await fetchJson(`/api/plans/${planId}${query}`)).plan);
  } catch (error) {
    checkStatus.textContent = error.message;
  }
}

async function save() {
  if (!mine) return;
  checkStatus.textContent = t("Saving…");
  try {
    const body = { text: text.value };
    if (nameInput) body.name = nameInput.value.trim();
    showPlan((await fetchJson(`/api/plans/${planId}`, { method: "PUT", body })).plan);
    checkStatus.textContent = t("Saved as version {latest}.", { latest: state.latest });
    checkStatus.dataset.valid = "true";
  } catch (error) {
    showErrors(error.payload?.errors ?? []);
    checkStatus.textContent = error.message;
    checkStatus.dataset.valid = "false";
    if (error.field === "name") nameInput?.setAttribute("aria-invalid", "true");
  }
}

async function copy() {
  try {
    const { plan } = await fetchJson(`/api/plans/${planId}/copy`, { method: "POST", body: {} });
    window.location.assign(`/plans/${plan.id}`);
  } catch (error) {
    checkStatus.textContent = error.message;
  }
}

async function share() {
  const value = root.querySelector("[data-field=share-course]").value;
  try {
    const { plan } = await fetchJson(`/api/plans/${planId}/share`, { method: "PUT",
      body: { course_id: value ? Number(value) : null } });
    showPlan({ ...plan });
    checkStatus.textContent = plan.shared_with ? t("Shared with {code}.", { code: plan.shared_with.code }) : t("No longer shared.");
  } catch (error) {
    checkStatus.textContent = error.message;
  }
}

async function useAsSkill(event) {
  const box = event.currentTarget;
  const wanted = box.checked;
  try {
    await fetchJson(`/api/plans/${planId}/skill`, { method: "PUT", body: { console_skill: wanted } });
    checkStatus.textContent = wanted
      ? t("This plan is now a panel in your consoles (the Navigate view): Run runs its latest version there.")
      : t("This plan is no longer a panel in your consoles.");
  } catch (error) {
    box.checked = !wanted;
    checkStatus.textContent = error.message;
  }
}

async function remove() {
  if (!window.confirm(t("Delete this plan and all its versions?"))) return;
  try {
    await fetchJson(`/api/plans/${planId}`, { method: "DELETE" });
    window.location.assign("/plans");
  } catch (error) {
    checkStatus.textContent = error.message;
  }
}

// --- the map -----------------------------------------------------------------------------------

function draw() {
  const width = canvas.clientWidth || canvas.width;
  const height = Math.round(width * 0.75);
  if (canvas.width !== width || canvas.height !== height) Object.assign(canvas, { width, height });
  const context = canvas.getContext("2d");
  const points = [...state.traces.predicted, ...state.traces.real];
  const bounds = sceneBounds(state.sceneBoxes);
  for (const p of points) {
    bounds.minX = Math.min(bounds.minX, p.x_m - 0.3); bounds.maxX = Math.max(bounds.maxX, p.x_m + 0.3);
    bounds.minY = Math.min(bounds.minY, p.y_m - 0.3); bounds.maxY = Math.max(bounds.maxY, p.y_m + 0.3);
  }
  const view = fitView(bounds, width, height);
  context.clearRect(0, 0, width, height);
  context.fillStyle = "#f4f6f8";
  context.fillRect(0, 0, width, height);
  context.fillStyle = "#7d8793";
  for (const box of state.sceneBoxes) {
    const corners = boxCorners(box).map(([x, y]) => worldToCanvas(view, x, y));
    context.beginPath();
    corners.forEach(([x, y], i) => (i ? context.lineTo(x, y) : context.moveTo(x, y)));
    context.closePath();
    context.fill();
  }
  for (const [kind, trace] of Object.entries(state.traces)) {
    if (!trace.length) continue;
    context.strokeStyle = context.fillStyle = TRACE_COLOURS[kind];
    context.lineWidth = kind === "predicted" ? 7 : 2.5;  // the prediction under the real run: both show where they meet
    context.globalAlpha = kind === "predicted" ? 0.55 : 1;
    context.beginPath();
    trace.forEach((p, i) => { const [x, y] = worldToCanvas(view, p.x_m, p.y_m); if (i) context.lineTo(x, y); else context.moveTo(x, y); });
    context.stroke();
    const [sx, sy] = worldToCanvas(view, trace[0].x_m, trace[0].y_m);
    context.strokeRect(sx - 4, sy - 4, 8, 8);
    const end = trace[trace.length - 1];
    const [ex, ey] = worldToCanvas(view, end.x_m, end.y_m);
    context.beginPath();
    context.arc(ex, ey, 5, 0, 2 * Math.PI);
    context.fill();
    context.globalAlpha = 1;
  }
  canvas.dataset.predictedPoints = String(state.traces.predicted.length);
  canvas.dataset.realPoints = String(state.traces.real.length);
  const error = endErrorCm(state.traces.predicted, state.traces.real);
  endErrorLine.textContent = error == null ? "" : t(" — end points {error} cm apart", { error: fixed(error, 1) });
}

async function loadScene(robotName) {
  try {
    const robot = await fetchJson(`/api/robots/${encodeURIComponent(robotName)}`);
    state.sceneBoxes = robot.info?.scene_boxes ?? [];
  } catch {
    state.sceneBoxes = [];
  }
  draw();
}

// --- runs --------------------------------------------------------------------------------------

function showLine(label, feedback) {
  const line = lineOf(feedback);
  if (line && line !== state.runningLine) { state.runningLine = line; renderGutter(); }
  if (line) progressLine.textContent = t("{label}: running line {line}: {value}", { label, line, value: String(feedback.state ?? "").replace(/^line \d+:\s*/, "") });
}

function setRunning(running) {
  button("cancel").hidden = !running;
  button("try").disabled = running;
  button("run").disabled = running;
}

function finish(run, goal) {
  if (run.finished) return;
  run.finished = true;
  endStateLine.textContent = `${run.label}: ${endStateWords(goal)}`;
  endStateLine.dataset.status = goal.status;
  root.dataset.lastEnd = goal.status;
  progressLine.textContent = "";
  state.runningLine = null;
  renderGutter();
  setRunning(false);
  if (run.prediction) { draw(); return; }  // its whole trace came with the stream's end
  // One more telemetry sample lands the trace where the robot stopped.
  setTimeout(() => { run.goalChannel.close(); run.telemetry.close(); draw(); }, 600);
}

function follow(answer, kind, label) {
  state.traces[kind] = [];
  const run = { answer, kind, label, finished: false };
  state.run = run;
  endStateLine.textContent = "";
  progressLine.textContent = t("{label}: started.", { label });
  setRunning(true);
  run.telemetry = new Channel(answer.telemetry_channel);
  run.telemetry.addEventListener("message", (event) => {
    const message = parseJsonMessage(event.detail);
    if (message?.type !== "telemetry") return;
    state.traces[kind] = addSample(state.traces[kind], message.odometry?.pose);
    draw();
  });
  run.goalChannel = new Channel(answer.goal_channel);
  run.goalChannel.addEventListener("message", (event) => {
    const message = parseJsonMessage(event.detail);
    if (!message || run.finished) return;
    const feedback = message.type === "goal_feedback" ? message.feedback : message.goal?.feedback;
    if (feedback) showLine(label, feedback);
    if (message.type === "goal" && isFinal(message.goal?.status)) finish(run, message.goal);
  });
  run.goalChannel.addEventListener("statechange", (event) => {
    if (event.detail.phase === "closed" && event.detail.code && event.detail.code !== 1000 && !run.finished) {
      progressLine.textContent = t("{label}: the run's progress cannot be followed ({reason}).", { label, reason: event.detail.reason });
      setRunning(false);
    }
  });
}

// Without a lab robot to stand beside, the prediction starts at the dock.
function practiceStartsAtDock() {
  return (root.querySelector("input[name=practice_start]:checked")?.value ?? "dock") === "dock";
}

// The prediction: the plan in fast mode on a throwaway simulated copy of the lab robot, streamed as JSON lines
// (the line running and the trace's new points, then the end). Cancel closes the stream; the server stops the copy.
function onPrediction(run, message) {
  if (message.type === "progress" && message.phase === "starting") {
    progressLine.textContent = `${run.label}: ${message.message}`;
  } else if (message.type === "started") {
    startLine.textContent = t("{label} on a fast simulated copy: {value}", { label: run.label, value: message.start?.message ?? "" });
    if (run.unsaved) startLine.textContent += t(" It runs version {unsaved}, as saved: save to predict your changes.", { unsaved: run.unsaved });
    progressLine.textContent = t("{label}: running…", { label: run.label });
  } else if (message.type === "progress") {
    const from = Number.isInteger(message.trace_from) ? message.trace_from : state.traces.predicted.length;
    state.traces.predicted = [...state.traces.predicted.slice(0, from), ...(message.trace ?? [])].slice(-5000);
    if (message.feedback) showLine(run.label, message.feedback);
    draw();
  } else if (message.type === "end") {
    state.traces.predicted = message.trace ?? state.traces.predicted;
    finish(run, message.goal);
    if (message.sim_time_s != null && message.wall_s != null) {
      startLine.textContent += t(" {sim_time_s} s of plan predicted in {wall_s} s.", { sim_time_s: fixed(message.sim_time_s, 1), wall_s: fixed(message.wall_s, 1) });
    }
  } else if (message.type === "error") {
    run.finished = true;
    progressLine.textContent = `${run.label}: ${message.error?.message ?? t("the prediction failed.")}`;
    if (message.trace) state.traces.predicted = message.trace;
    setRunning(false);
    draw();
  }
}

async function predict() {
  if (!(await check())) return;
  const robotName = robotSelect?.value ?? "";
  const run = { label: t("Prediction"), prediction: true, finished: false, abort: new AbortController(),
    unsaved: state.saved && text.value.trim() !== state.saved.text.trim() ? state.saved.version : null };
  state.run = run;
  state.traces.predicted = [];
  draw();
  progressLine.textContent = t("Prediction: starting…");
  endStateLine.textContent = "";
  delete endStateLine.dataset.status;
  startLine.textContent = "";
  setRunning(true);
  try {
    await fetchJsonLines(`/api/plans/${planId}/predictions`,
      { body: { beside: robotName || null, from_dock: practiceStartsAtDock(), version: state.saved?.version ?? null },
        signal: run.abort.signal },
      (message) => onPrediction(run, message));
    if (!run.finished) {
      progressLine.textContent = t("Prediction: the answer ended early; try again.");
      setRunning(false);
    }
  } catch (error) {
    run.finished = true;
    progressLine.textContent = error.name === "AbortError" ? t("Prediction: cancelled.") : t("Prediction: {message}", { message: error.message });
    setRunning(false);
  }
}

async function startRun(target) {
  if (!(await check())) return;
  const robotName = robotSelect?.value ?? "";
  progressLine.textContent = t("Starting on {robotName}…", { robotName });
  endStateLine.textContent = "";
  try {
    const answer = await fetchJson(`/api/plans/${planId}/runs`,
      { method: "POST", body: { target, version: state.saved?.version ?? null } });
    follow(answer, "real", answer.robot);
  } catch (error) {
    progressLine.textContent = error.message;
    setRunning(false);
  }
}

async function cancel() {
  if (!state.run) return;
  if (state.run.prediction) { state.run.abort.abort(); return; }
  try {
    await fetchJson(state.run.answer.cancel_url, { method: "DELETE" });
  } catch (error) {
    progressLine.textContent = error.message;
  }
}

function queueForRobot() {
  const robotName = robotSelect?.value;
  if (!robotName) return;
  state.queue?.close();
  turnLine.textContent = t("Joining {robotName}'s queue…", { robotName });
  state.queue = new Channel(`/ws/robots/${encodeURIComponent(robotName)}/queue`);
  state.queue.addEventListener("message", (event) => {
    const seat = parseJsonMessage(event.detail);
    if (seat?.type !== "queue") return;
    button("run").hidden = !seat.is_controller;
    button("run").textContent = t("Run on {robotName}", { robotName });
    turnLine.textContent = seat.is_controller
      ? t("Your turn on {robotName}{value}.", { robotName, value: seat.turn_remaining_s != null ? t(" ({turn_remaining_s} s left)", { turn_remaining_s: Math.round(seat.turn_remaining_s) }) : "" })
      : t("Waiting for {robotName}: position {value} of {queue_size}{value2}.", { robotName, value: seat.position ?? "?", queue_size: seat.queue_size, value2: seat.controller ? t(", {controller} has it", { controller: seat.controller }) : "" });
  });
}

// --- wiring ------------------------------------------------------------------------------------

text.addEventListener("input", () => { if (state.errors.length) showErrors([]); else renderGutter(); });
text.addEventListener("scroll", () => { gutter.scrollTop = text.scrollTop; });
text.addEventListener("keydown", (event) => {
  if ((event.ctrlKey || event.metaKey) && event.key === "Enter") { event.preventDefault(); check(); }
  if ((event.ctrlKey || event.metaKey) && event.key.toLowerCase() === "s") { event.preventDefault(); save(); }
});
versionSelect.addEventListener("change", () => load(Number(versionSelect.value)));
button("check").addEventListener("click", check);
button("save")?.addEventListener("click", save);
button("copy").addEventListener("click", copy);
button("share")?.addEventListener("click", share);
button("delete")?.addEventListener("click", remove);
root.querySelector("input[name=console_skill]")?.addEventListener("change", useAsSkill);
button("try").addEventListener("click", predict);
button("run").addEventListener("click", () => startRun(robotSelect.value));
button("cancel").addEventListener("click", cancel);
button("queue").addEventListener("click", queueForRobot);
robotSelect?.addEventListener("change", () => { loadScene(robotSelect.value); button("run").hidden = true;
  if (startRobotName) startRobotName.textContent = robotSelect.value;
  state.queue?.close(); turnLine.textContent = ""; });
window.addEventListener("resize", draw);
if (robotSelect?.value) loadScene(robotSelect.value); else draw();
load();
