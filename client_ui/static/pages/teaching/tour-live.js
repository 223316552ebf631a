// A live guided class: every page follows the tutor's step through /ws/tour-sessions/<id>; the tutor moves
// the class, runs a step's skill, and hands the robot to a student and back. Questions go in the robot's chat.
// The robot's camera, drive pad and the panels the steps name are the console's own (robot-panels.js): a student
// handed the robot drives it from here.
import { Channel, fetchJson, parseJsonMessage } from "../../lib/transport.js";
import { panelTitle, showRobotPanels } from "../../lib/console/robot-panels.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("live");
const sessionId = Number(root.dataset.sessionId);
const tourId = Number(root.dataset.tourId);
const robot = root.dataset.robot;
const me = root.dataset.me;
const isTutor = root.dataset.tutor === "true";
const field = (name) => root.querySelector(`[data-field=${name}]`);
let state = null;
let robotPanels = { titles: new Map(), shown: new Set(), highlight: () => {} };

function render(next) {
  state = next;
  root.dataset.step = String(next.step_index);
  root.dataset.controller = next.controller ?? "";
  field("progress").textContent = t("Step {value} of {step_count}", { value: next.step_index + 1, step_count: next.step_count });
  field("step-title").textContent = next.step?.title || t("Step {value}", { value: next.step_index + 1 });
  field("step-text").textContent = next.step?.text ?? "";
  field("step-panel").textContent = next.step ? panelTitle(robotPanels.titles, next.step.panel) : "";
  robotPanels.highlight(next.step?.panel);
  field("control").textContent = next.ended ? t("The class has ended.")
    : next.controller === me ? t("You have control of the robot.") : t("{controller} has control of the robot.", { controller: next.controller });
  field("participants").textContent = next.participants.join(", ");
  if (isTutor) {
    const select = root.querySelector("[data-field=hand-to]");
    const chosen = select.value;
    select.replaceChildren(...next.participants.filter((n) => n !== me).map((name) => {
      const option = document.createElement("option");
      option.value = option.textContent = name;
      return option;
    }));
    if (chosen) select.value = chosen;
    root.querySelector("[data-action=prev]").disabled = next.step_index === 0;
    root.querySelector("[data-action=next]").disabled = next.step_index >= next.step_count - 1;
    root.querySelector("[data-action=run]").disabled = !next.step?.command;
  }
}

async function act(body) {
  try {
    render(await fetchJson(`/api/tour-sessions/${sessionId}`, { method: "POST", body }));
    field("error").textContent = "";
  } catch (error) {
    field("error").textContent = error.message;
  }
}

if (isTutor) {
  root.querySelector("[data-action=prev]").addEventListener("click", () => act({ action: "step", index: state.step_index - 1 }));
  root.querySelector("[data-action=next]").addEventListener("click", () => act({ action: "step", index: state.step_index + 1 }));
  root.querySelector("[data-action=hand]").addEventListener("click", () => {
    const name = root.querySelector("[data-field=hand-to]").value;
    if (name) act({ action: "control", user: name });
  });
  root.querySelector("[data-action=take]").addEventListener("click", () => act({ action: "control", user: null }));
  root.querySelector("[data-action=end]").addEventListener("click", () => act({ action: "end" }));
  root.querySelector("[data-action=run]").addEventListener("click", async () => {
    try {
      const answer = await fetchJson(`/api/tours/${tourId}/steps/${state.step_index}/run`, { method: "POST",
        body: { target: robot } });
      field("error").textContent = answer.goal ? t("Running: goal {status}.", { status: answer.goal.status }) : t("Done.");
    } catch (error) {
      field("error").textContent = error.message;
    }
  });
}

// Joining the robot's queue (the drive channel, which the drive pad opens) is what lets the access rule give
// this person the robot.
async function showPanels() {
  let named = [];
  try {
    named = (await fetchJson(`/api/tours/${tourId}`)).steps.map((step) => step.panel);
  } catch { /* the camera and the drive pad still help */ }
  robotPanels = await showRobotPanels(root.querySelector("[data-slot=robot-panels]"), robot, ["camera", "drive", ...named]);
  if (!robotPanels.shown.has("drive")) new Channel(`/ws/robots/${robot}/drive`);
  if (state) render(state);
}
showPanels();
const sessionChannel = new Channel(`/ws/tour-sessions/${sessionId}`);
sessionChannel.addEventListener("message", (event) => {
  const message = parseJsonMessage(event.detail);
  if (message?.type === "state") render(message);
});

// Questions: the robot's chat.
const chatList = root.querySelector("[data-slot=chat]");
const chat = new Channel(`/ws/robots/${robot}/chat`);
function addMessage(message) {
  const item = document.createElement("li");
  item.textContent = `${message.author}: ${message.body}`;
  chatList.append(item);
  while (chatList.children.length > 50) chatList.firstElementChild.remove();
}
chat.addEventListener("message", (event) => {
  const message = parseJsonMessage(event.detail);
  if (message?.type === "history") { chatList.replaceChildren(); message.messages.forEach(addMessage); }
  if (message?.type === "message") addMessage(message.message);
});
root.querySelector("[data-form=chat]").addEventListener("submit", (event) => {
  event.preventDefault();
  const input = event.target.querySelector("input");
  if (!input.value.trim()) return;
  chat.sendJson({ type: "say", body: input.value });
  input.value = "";
});
