// The fully guided tour page: the engine runs the steps on the learner's practice robot, whose panels that the
// steps name are shown below the step, the current one marked.
import { fetchJson } from "../../lib/transport.js";
import { TourEngine, abortableSleep } from "./tour-engine.js";
import { panelTitle, showRobotPanels } from "../../lib/console/robot-panels.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("tour");
const tourId = Number(root.dataset.tourId);
const stepTitle = root.querySelector("[data-field=step-title]");
const stepText = root.querySelector("[data-field=step-text]");
const stepPanel = root.querySelector("[data-field=step-panel]");
const progress = root.querySelector("[data-field=progress]");
const statusLine = root.querySelector("[data-field=status]");
const buttons = Object.fromEntries([...root.querySelectorAll("[data-action]")].map((b) => [b.dataset.action, b]));
const FINAL = new Set(["succeeded", "canceled", "aborted"]);
let engine = null;
let robotPanels = { titles: new Map(), highlight: () => {} };

let followedNoted = false;

function render(state) {
  if (state.status === "done" && root.dataset.status !== "done" && !followedNoted) {
    followedNoted = true;  // once per page: the tutors' analytics counts the tour followed to its end
    fetchJson(`/api/tours/${tourId}/followed`, { method: "POST" }).catch(() => { followedNoted = false; });
  }
  root.dataset.status = state.status;
  root.dataset.index = String(state.index);
  progress.textContent = t("Step {value} of {count}", { value: state.index + 1, count: state.count });
  const words = { ready: t("Ready."), running: t("Running the step…"), waiting: t("Watching…"), paused: t("Paused."),
    done: t("Done."), failed: t("Stopped.") };
  statusLine.textContent = state.message || words[state.status];
  buttons.start.hidden = state.status !== "ready";
  buttons.pause.hidden = !["running", "waiting"].includes(state.status);
  buttons.resume.hidden = state.status !== "paused";
  buttons.next.hidden = !(state.status === "waiting" && engine?.steps[state.index]?.condition?.type === "manual");
  buttons.replay.hidden = state.status === "ready";
}

const io = {
  show(index, step) {
    stepTitle.textContent = step.title || t("Step {value}", { value: index + 1 });
    stepText.textContent = step.text;
    stepPanel.textContent = panelTitle(robotPanels.titles, step.panel);
    robotPanels.highlight(step.panel);
  },
  async run(index) {
    const answer = await fetchJson(`/api/tours/${tourId}/steps/${index}/run`, { method: "POST",
      body: { target: "practice" } });
    return answer.goal ? answer.goal.goal_id : null;
  },
  async waitGoal(goalId, signal) {
    // Goals end in seconds to minutes; a half-second look is plenty for a step that waits for one.
    for (;;) {
      await abortableSleep(500, signal);
      const answer = await fetchJson(`/api/robots/practice/command-goals/${goalId}`, { signal });
      if (FINAL.has(answer.goal.status)) return answer.goal.status;
    }
  },
  sleep: abortableSleep,
  async stop() {
    try { await fetchJson("/api/lessons/stop", { method: "POST", body: { target: "practice" } }); } catch { /* off */ }
  },
  changed: render,
};

async function ensurePracticeRobot() {
  statusLine.textContent = t("Starting your practice robot…");
  const state = await fetchJson("/api/practice", { method: "POST" });
  const wanted = ["camera", ...engine.steps.map((step) => step.panel)];
  robotPanels = await showRobotPanels(root.querySelector("[data-slot=robot-panels]"), state.name, wanted);
  return state;
}

async function main() {
  const tour = await fetchJson(`/api/tours/${tourId}`);
  engine = new TourEngine(tour.steps, io);
  render(engine.state);
  buttons.start.addEventListener("click", async () => {
    try {
      await ensurePracticeRobot();
    } catch (error) {
      statusLine.textContent = error.message;
      return;
    }
    engine.start();
  });
  buttons.pause.addEventListener("click", () => engine.pause());
  buttons.resume.addEventListener("click", () => engine.resume());
  buttons.next.addEventListener("click", () => engine.next());
  buttons.replay.addEventListener("click", () => engine.replay());
  root.dataset.ready = "true";
}

main().catch((error) => { statusLine.textContent = error.message; });
