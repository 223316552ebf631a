// An exercise's page: the CodeMirror editor, Run (the practice robot) and Submit (a hidden start, graded, on a fresh
// simulated robot, or on a lab robot in the student's turn: lab-turn.js), Stop, the console, and the grade with the
// robot's true path, which the server measured from the robot's own record.
import { EditorView, basicSetup } from "codemirror";
import { EditorState, StateEffect, StateField } from "@codemirror/state";
import { Decoration } from "@codemirror/view";
import { python } from "@codemirror/lang-python";
import { fetchJson } from "../../lib/transport.js";
import { PythonWorker, RobotRun } from "./exercise-run.js";
import { LabTurn } from "./lab-turn.js";
import { drawTrace } from "./trace-map.js";
import { measurementRow } from "./measurements.js";
import { fixed, t } from "../../lib/i18n.js";

const root = document.getElementById("exercise");
const slug = root.dataset.slug;
const statusLine = root.querySelector("[data-field=status]");
const consolePane = root.querySelector("[data-field=console]");
const gradeLine = root.querySelector("[data-field=grade]");
const measurements = root.querySelector("[data-slot=measurements]");
const runsList = root.querySelector("[data-slot=runs]");
const map = root.querySelector("[data-slot=map]");
const robotLine = root.querySelector("[data-field=robot]");
let rubric = null;  // what the run is measured by (the trace map draws a follow_line rubric's line)
const buttons = Object.fromEntries([...root.querySelectorAll("[data-action]")].map((b) => [b.dataset.action, b]));
const labTurn = new LabTurn(root.querySelector("[data-slot=lab]"));
const PRACTICE_POLL_MS = 1000;
const PRACTICE_WAIT_MS = 120000;

let template = "";
let current = null;  // { run, robotRun }
let pythonReady = false;
// Read by the benchmark: Pyodide's load, each tick's time, and per acknowledged command the time from the page's
// send (what the drive pad measures) and from the student's code (tick -> worker -> page -> socket -> robot).
export const timings = { pyodide_load_s: null, ticks: [], pad_ack_ms: [], code_ack_ms: [] };
window.telelabExercise = timings;

// ---- the editor, with the line of an error marked ----
const markError = StateEffect.define();
const errorLine = StateField.define({
  create: () => Decoration.none,
  update(marks, transaction) {
    marks = marks.map(transaction.changes);
    for (const effect of transaction.effects) {
      if (effect.is(markError)) {
        marks = effect.value === null ? Decoration.none
          : Decoration.set([Decoration.line({ class: "exercise__error-line" }).range(effect.value)]);
      }
    }
    return transaction.docChanged ? Decoration.none : marks;
  },
  provide: (field) => EditorView.decorations.from(field),
});
const editor = new EditorView({
  parent: root.querySelector("[data-slot=editor]"),
  state: EditorState.create({ doc: "", extensions: [basicSetup, python(), errorLine, EditorView.lineWrapping,
    EditorView.cspNonce.of(root.dataset.styleNonce ?? "")] }),
});

/** The program as Python reads it: a no-break space (pasted from a web page) is a space. */
function code() {
  return editor.state.doc.toString().replace(/\u00a0/g, " ");
}

function setCode(text) {
  editor.dispatch({ changes: { from: 0, to: editor.state.doc.length, insert: text } });
}

function showError(line) {
  if (!line || line > editor.state.doc.lines) return;
  const at = editor.state.doc.line(line);
  editor.dispatch({ effects: [markError.of(at.from), EditorView.scrollIntoView(at.from, { y: "center" })],
                    selection: { anchor: at.from } });
}

// ---- console and status ----
function say(text, kind = "info") {
  statusLine.textContent = text;
  statusLine.dataset.kind = kind;
}

function print(line, stream = "stdout") {
  const span = document.createElement("span");
  span.className = stream;
  span.textContent = line + "\n";
  consolePane.append(span);
  while (consolePane.childNodes.length > 500) consolePane.firstChild.remove();
  consolePane.scrollTop = consolePane.scrollHeight;
}

function setRunning(running) {
  buttons.run.disabled = buttons.submit.disabled = running || !pythonReady;
  buttons.stop.disabled = !running;
  buttons.reset.disabled = running;
  labTurn.setBusy({ running, runningOn: current?.run.robot_name, ready: pythonReady });
}

// ---- Python ----
// The worker shares memory with the page (SharedArrayBuffer), which only an isolated page has: none is made otherwise.
const python3 = window.crossOriginIsolated ? new PythonWorker() : null;
function awaitPython(ready, again = false) {
  ready.then((message) => {
    pythonReady = true;
    timings.pyodide_load_s ??= message.load_s;
    root.dataset.pythonReady = "true";
    // Loaded again after a Stop: said in the console, so the run's grade stays on the status line.
    if (again) print(t("Python has loaded again: you can run your program."));
    else say(t("Python {version} is ready (loaded in {load_s} s).", { version: message.version, load_s: fixed(message.load_s, 1) }));
    setRunning(Boolean(current));
  }, (error) => say(t("Python did not load: {message}", { message: error.message }), "error"));
}
if (python3) {
  awaitPython(python3.ready);
  // A program that ignored Stop had its worker replaced: Run waits until the new interpreter has loaded.
  python3.addEventListener("restarting", (event) => {
    pythonReady = false;
    root.dataset.pythonReady = "false";
    awaitPython(event.detail, true);
  });
}

if (window.self !== window.top && !window.crossOriginIsolated) {
  // Framed by an LMS, the page cannot be isolated (its parent is not): the program needs a window of its own.
  document.querySelector("[data-slot=own-window]").hidden = false;
  say(t("Python exercises run in a window of their own, not inside another site's page."), "error");
} else if (!window.crossOriginIsolated) {
  say(t("This page needs a browser that isolates it (SharedArrayBuffer): a current Chromium, Firefox or Safari."), "error");
}


// ---- the practice robot ----
async function practiceRobot() {
  let state = await fetchJson("/api/practice");
  if (state.running) return state.name;
  if (!state.starting) {
    say(t("Starting your practice robot…"));
    state = await fetchJson("/api/practice", { method: "POST" });
  }
  const until = Date.now() + PRACTICE_WAIT_MS;
  // A robot neither running nor starting any more is a start that died: said now, not after the whole wait.
  while (!state.running && state.starting && Date.now() < until) {
    await new Promise((resolve) => setTimeout(resolve, PRACTICE_POLL_MS));
    state = await fetchJson("/api/practice");
  }
  if (!state.running) throw new Error(t("Your practice robot did not start. Try again in a moment."));
  return state.name;
}

// ---- a run ----
/** Runs the code on robot: "practice" (the user's practice robot, started if need be; a submission restarts it
 * fresh) or a lab robot in the user's turn. */
async function start(mode, robot = "practice") {
  setRunning(true);
  editor.dispatch({ effects: markError.of(null) });
  consolePane.textContent = "";
  try {
    if (robot === "practice") await practiceRobot();
    say(mode === "submission" ? t("Placing the robot at a hidden start…") : t("Placing the robot at the start…"));
    const answer = await fetchJson(`/api/exercises/${encodeURIComponent(slug)}/runs`, { method: "POST",
      body: { code: code(), mode, robot } });
    const run = answer.run;
    const robotRun = new RobotRun(python3, run.robot_name);
    current = { run, robotRun };
    setRunning(true);  // the lab robot's line says the run keeps the turn
    robotRun.addEventListener("print", (event) => print(event.detail.line, event.detail.stream));
    robotRun.addEventListener("ack", (event) => {
      if (event.detail.sent_at !== undefined) timings.pad_ack_ms.push(performance.now() - event.detail.sent_at);
      if (event.detail.code_at) timings.code_ack_ms.push(performance.timeOrigin + performance.now() - event.detail.code_at);
    });
    robotRun.addEventListener("tick", (event) => { if (timings.ticks.length < 20000) timings.ticks.push(event.detail.at); });
    robotRun.addEventListener("telemetry", (event) => showOdometry(event.detail));
    robotRun.addEventListener("state", () => print(t("No robot.tick() for a while: the robot was stopped."), "stderr"));
    robotRun.addEventListener("done", (event) => finish(event.detail));
    const ready = await robotRun.connect();
    if (ready.is_controller === false) throw new Error(t("You do not control this robot now."));
    root.dataset.running = "true";
    say(t("Running on {robot_name} ({time_limit_s} s at most). Stop ends it now.", { robot_name: run.robot_name, time_limit_s: answer.exercise.time_limit_s }));
    robotRun.start(code(), { max_linear_mps: ready.max_linear_mps,
      max_angular_radps: ready.max_angular_radps, time_limit_s: answer.exercise.time_limit_s });
  } catch (error) {
    say(error.message, "error");
    current?.robotRun.close();
    current = null;
    setRunning(false);
  }
}

async function finish(outcome) {
  const { run, robotRun } = current;
  robotRun.close();
  root.dataset.running = "false";
  // The robot refused the run's commands (the turn on a lab robot ended): said as the command path said it.
  const ended = outcome.refused ? t("The run ended: {message}", { message: outcome.refused }) : "";
  if (ended) print(ended, "stderr");
  else if (outcome.ok) print(t("Your program ended."));
  else if (outcome.stopped) print(t("Stopped: the robot was stopped."), "stderr");
  else {
    if (outcome.traceback) print(outcome.traceback.trimEnd(), "stderr");
    print(outcome.line ? t("Line {line}: {message}", { line: outcome.line, message: outcome.message }) : outcome.message, "stderr");
    showError(outcome.line);
  }
  if (ended) say(`${ended} ${t("Measuring the run from the robot's record…")}`, "error");
  else say(outcome.ok || outcome.stopped ? t("Measuring the run from the robot's record…")
    : t("Your program failed{value}: {message}. Measuring what the robot did…", { value: outcome.line ? t(" at line {line}", { line: outcome.line }) : "", message: outcome.message }),
  outcome.ok || outcome.stopped ? "info" : "error");
  try {
    const body = outcome.report ? { report: outcome.report } : {};
    const answer = await fetchJson(`/api/exercise-runs/${run.id}/finish`, { method: "POST", body });
    showGrade(answer.run, answer.scene_boxes);
    if (ended) say(`${ended} ${t("What the robot did until then is graded below.")}`, "error");
    else if (outcome.ok || outcome.stopped) say(answer.run.status === "graded" ? t("Run graded.") : answer.run.feedback);
    else say(t("Your program failed{value}: {message}. ", { value: outcome.line ? t(" at line {line}", { line: outcome.line }) : "", message: outcome.message })
      + t("What the robot did until then is graded below."), "error");
  } catch (error) {
    say(error.message, "error");
  }
  current = null;
  setRunning(false);
  loadRuns();
}

function showOdometry(message) {
  const { pose, linear_mps: v } = message.odometry;
  robotLine.textContent = `${current?.run.robot_name ?? "Robot"}: x ${fixed(pose.x_m, 2)} m, y ${fixed(pose.y_m, 2)} m, `
    + t("heading {value}°, speed {v} m/s", { value: fixed(pose.theta_rad * 180 / Math.PI, 0), v: fixed(v, 2) });
  const line = message.line?.values;
  if (Array.isArray(line) && line.length) {
    robotLine.textContent += t(", line sensor {values}", { values: line.map((value) => fixed(value, 1)).join(" ") });
    robotLine.dataset.line = line.join(" ");
  }
  robotLine.dataset.speed = String(v);
  robotLine.dataset.x = String(pose.x_m);
}

function showGrade(run, boxes) {
  const kind = run.mode === "submission" ? t("Submission") : t("Practice run");
  gradeLine.classList.remove("muted");
  gradeLine.textContent = run.grade === null ? `${kind}: ${run.feedback}`
    : `${kind} #${run.id}: ${Math.round(run.grade * 100)}% — ${run.feedback}`;
  gradeLine.dataset.grade = run.grade ?? "";
  const body = measurements.querySelector("tbody");
  body.replaceChildren(...run.measurements.map((m) => {
    const row = document.createElement("tr");
    for (const text of measurementRow(m)) {
      const cell = document.createElement("td");
      cell.textContent = text;
      row.append(cell);
    }
    return row;
  }));
  measurements.hidden = !run.measurements.length;
  drawTrace(map, boxes ?? [], run.trace ?? [], run.start, rubric);
}

async function loadRuns() {
  const answer = await fetchJson(`/api/exercises/${encodeURIComponent(slug)}`);
  runsList.replaceChildren(...answer.runs.map((run) => {
    const item = document.createElement("li");
    const status = run.status === "running" ? t("running") : t("failed"); // a run without a grade
    const grade = run.grade === null ? status : `${Math.round(run.grade * 100)}%`;
    const mode = run.mode === "submission" ? t("submission") : t("practice");
    item.textContent = `#${run.id} ${mode} · ${grade} · ${run.started_at.slice(0, 16).replace("T", " ")}`;
    return item;
  }));
  return answer;
}

buttons.run.addEventListener("click", () => start("practice"));
buttons.submit.addEventListener("click", () => start("submission"));
buttons["lab-submit"].addEventListener("click", () => { if (labTurn.controlled) start("submission", labTurn.controlled); });
// The turn on the run's lab robot ended (it passed, or the student was dropped from the queue): the run ends now,
// never waits for its time limit while every command is refused.
labTurn.addEventListener("seat", ({ detail }) => {
  if (current?.run.robot_name === detail.robot_name && !detail.seat?.is_controller) {
    current.robotRun.endRefused(t("your turn on {robot_name} ended, so it takes no more of your commands.", { robot_name: detail.robot_name }));
  }
});
buttons.stop.addEventListener("click", () => { say(t("Stopping…")); current?.robotRun.stop(); });
buttons.reset.addEventListener("click", () => setCode(template));
// A closed or hidden tab: the robot stops now (the drive socket's close stops it too, and else the deadman).
addEventListener("pagehide", () => { current?.robotRun.stop(); current?.robotRun.close(); });

loadRuns().then((answer) => {
  template = answer.exercise.template;
  rubric = answer.exercise.rubric;
  setCode(answer.code);
}, (error) => say(error.message, "error"));
setRunning(false);
labTurn.load().catch((error) => say(error.message, "error"));
