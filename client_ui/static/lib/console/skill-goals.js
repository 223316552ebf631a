// The skill panels' feed service ("skill-goals"): a skill's Activate and Cancel through the skills API (a plan used
// as a skill through the plans API, its run_url), timed for the response-times panel; the goal followed on its socket
// until it ends; the robot's running goals, whoever started them, adopted every GOALS_POLL_MS (a goal started in
// another tab, by a tour's step, or before the console opened again shows); a pose-guess skill told the robot's best
// pose. A goal's feedback goes out on the wiring as "goal-feedback" (the maps and the lab view draw it); a panel
// observes while the queue's "seat" says someone else controls the robot. The maps aim and start the first skill with
// goal x/y parameters through aimGoalSkill / startGoalSkill.

import { Channel, fetchJson, parseJsonMessage } from "../transport.js";
import { GUESS_FIELDS, goalParameterNames } from "../panel-descriptors.js";
import { perConsole, registerFeedService } from "./feed-services.js";
import { timeActivation } from "./timing-wiring.js";
import { t } from "../i18n.js";

const FINAL_GOAL_STATES = new Set(["succeeded", "canceled", "aborted"]);
const GOALS_POLL_MS = 2000; // a goal started elsewhere (another tab, a tour's step, a console opened again) shows

const skillsOf = perConsole(() => []); // [{descriptor, panel, goalChannel, goalId, goalNames}]

function robotApi(wiring) {
  return `/api/robots/${encodeURIComponent(wiring.robotName)}`;
}

/** The first skill whose schema has goal x/y parameters (go to goal), or undefined. */
function goalSkill(wiring) {
  return skillsOf(wiring).find((entry) => entry.goalNames);
}

/** Whether the console has a skill a map's target can start. */
export function hasGoalSkill(wiring) {
  return Boolean(goalSkill(wiring));
}

/** A target picked on a map becomes the goal skill's parameters; false when there is no goal skill. */
export function aimGoalSkill(wiring, x_m, y_m) {
  const skill = goalSkill(wiring);
  if (!skill) return false;
  skill.panel.parameters = { [skill.goalNames.x]: x_m, [skill.goalNames.y]: y_m };
  return true;
}

/** "Go there": the target as a goal of the goal skill, through the skill API like its Activate. */
export function startGoalSkill(wiring, x_m, y_m) {
  const skill = goalSkill(wiring);
  if (!skill) return;
  const parameters = { [skill.goalNames.x]: x_m, [skill.goalNames.y]: y_m };
  activate(wiring, skill, { skill: skill.descriptor.skill, parameters, preempt: true });
}

async function activate(wiring, entry, { skill, parameters, preempt }) {
  try {
    // A plan used as a skill runs through the plans API, on this robot; any other skill is activated.
    const runUrl = entry.descriptor.run_url;
    const body = runUrl ? { target: wiring.robotName } : { parameters, preempt: Boolean(preempt) };
    const answer = await timeActivation(wiring.timings, body, () => (runUrl
      ? fetchJson(runUrl, { method: "POST", body })
      : fetchJson(`${robotApi(wiring)}/skills/${encodeURIComponent(skill)}/goals`, { method: "POST", body })));
    followGoal(wiring, entry, answer.goal);
  } catch (error) {
    entry.panel.error = { code: error.code ?? "network", message: error.message, field: error.field ?? null };
  }
}

/** The robot's running goals, whoever started them: each skill panel shows and follows its skill's, so a panel
 *  never says Idle while its skill runs. */
async function adoptRunningGoals(wiring) {
  const skills = skillsOf(wiring);
  if (document.visibilityState !== "visible" || !skills.some((entry) => wiring.layout.isShown(entry.descriptor.id))) return;
  let answer;
  try {
    answer = await fetchJson(`${robotApi(wiring)}/goals`);
  } catch {
    return; // the next look tries again; the robot's line already says when it does not answer
  }
  for (const goal of answer?.goals ?? []) {
    const entry = skills.find((candidate) => candidate.descriptor.skill === goal.skill);
    if (entry && entry.goalId !== goal.goal_id) followGoal(wiring, entry, goal);
  }
}

/** Show a goal and follow it on its socket until it ends. */
function followGoal(wiring, entry, goal) {
  const { descriptor, panel } = entry;
  entry.goalId = goal?.goal_id ?? null;
  wiring.guard(descriptor.id, () => { panel.goal = goal; });
  entry.goalChannel?.close("a newer goal replaced it");
  if (!goal?.goal_id || FINAL_GOAL_STATES.has(goal.status)) return;
  const channel = new Channel(`${wiring.robotPath}/goals/${encodeURIComponent(goal.goal_id)}`);
  entry.goalChannel = channel;
  channel.addEventListener("message", ({ detail }) => {
    const message = parseJsonMessage(detail);
    if (!message) {
      wiring.layout.notify(descriptor.id, t("Ignored a goal message that could not be read."));
      return;
    }
    wiring.guard(descriptor.id, () => {
      if (message.type === "goal" && message.goal) {
        panel.goal = message.goal;
        const ended = FINAL_GOAL_STATES.has(message.goal.status);
        if (message.goal.feedback) shareFeedback(wiring, entry, message.goal.feedback, ended);
        if (ended) channel.close("the goal ended");
      } else if (message.type === "goal_event") {
        panel.goalEvent = message;
      } else if (message.type === "goal_feedback") {
        panel.feedback = message.feedback;
        shareFeedback(wiring, entry, message.feedback);
      } else if (message.type === "error") {
        panel.error = { code: message.code, message: message.message, field: null };
      }
    });
  });
}

/** Go-to-goal style feedback also shows on the maps (its goal and any obstacle values). */
function shareFeedback(wiring, entry, feedback, ended = false) {
  if (!entry.goalNames) return;
  // An ended goal's path is followed no more: its goal stays shown, its path goes.
  const shown = ended ? { ...feedback, planned_path: [] } : feedback;
  wiring.dispatchEvent(new CustomEvent("goal-feedback", { detail: shown }));
}

/** Keeps a pose-guess skill's panel told the robot's best pose: the converged estimate, else the pose tracked
 *  against the floor plan, else odometry. */
function followPose(wiring, descriptor, panel) {
  let estimate = null;
  wiring.listen(`${wiring.robotPath}/telemetry`, descriptor.id, (message) => {
    if (message.type === "localization") {
      const tracked = message.navigation?.source === "map tracking" ? message.navigation.pose : null;
      estimate = (message.active && message.converged ? message.estimate : null) ?? tracked;
      if (estimate) panel.currentPose = estimate;
    } else if (message.type === "telemetry" && !estimate && message.odometry?.pose) {
      panel.currentPose = message.odometry.pose;
    }
  });
}

/** Connects a skill panel: Activate, Cancel, its goals followed, the robot's running goals adopted. */
export function connectSkill(wiring, descriptor, panel) {
  panel.descriptor = descriptor;
  if (descriptor.schema?.some((parameter) => parameter.name === GUESS_FIELDS.x)) followPose(wiring, descriptor, panel);
  const entry = { descriptor, panel, goalChannel: null, goalId: null, goalNames: goalParameterNames(descriptor.schema) };
  const skills = skillsOf(wiring);
  if (!skills.length) {
    wiring.onStart(() => {
      adoptRunningGoals(wiring);
      setInterval(() => adoptRunningGoals(wiring), GOALS_POLL_MS);
    });
  }
  skills.push(entry);
  panel.addEventListener("skill-activate", ({ detail }) => activate(wiring, entry, detail));
  panel.addEventListener("skill-cancel", async ({ detail }) => {
    try {
      const answer = await fetchJson(`${robotApi(wiring)}/goals/${encodeURIComponent(detail.goal_id)}`, { method: "DELETE" });
      wiring.guard(descriptor.id, () => { panel.goal = answer.goal; });
    } catch (error) {
      panel.error = { code: error.code ?? "network", message: error.message, field: null };
    }
  });
  wiring.addEventListener("seat", ({ detail }) => { panel.observing = !detail.is_controller; });
}

registerFeedService("skill-goals", connectSkill);
