// The student's side of the class wall, on their class page: raise a hand (with a sentence), see at once when the
// tutor holds their robot, and read the tutor's notes, pointers and what they sent the class.
import { Channel, fetchJson, parseJsonMessage } from "../../lib/transport.js";
import { connectChat } from "../../lib/console/chat-session.js";
import { register as registerChatPanel } from "../../panels/chat-panel/chat-panel.js";
import { drawTile, floorPlan } from "./class-wall-draw.js";
import { DATE_LOCALE, t } from "../../lib/i18n.js";

const root = document.getElementById("class-help");
const form = root.querySelector("[data-field=hand-form]");
const lowerButton = root.querySelector("[data-action=lower]");
const handLine = root.querySelector("[data-field=hand]");
const heldLine = root.querySelector("[data-field=held]");
const notices = root.querySelector("[data-field=notices]");
const PUSH_WORDS = {
  lesson: t("Open the lesson"), exercise: t("Open the exercise"), plan: t("Open the plan"), test: t("Open the test"),
};
let channel = null;
let boxes = null;

function render(seat) {
  root.hidden = !seat.open;
  if (!seat.open) return;
  root.dataset.held = String(Boolean(seat.held_by));
  heldLine.hidden = !seat.held_by;
  heldLine.textContent = !seat.held_by ? ""
    : t("Your tutor {tutor} has taken over your robot: your commands wait until they give it back.", {
      tutor: seat.held_by });
  lowerButton.hidden = !seat.hand;
  form.querySelector("[data-action=raise]").textContent = seat.hand ? t("Change my question") : t("Raise my hand");
  handLine.textContent = !seat.hand ? "" : seat.hand.text
    ? t("Your hand is up: “{text}”. Your tutor sees it on the class wall.", { text: seat.hand.text })
    : t("Your hand is up. Your tutor sees it on the class wall.");
  const items = seat.notices.map(noticeItem);
  notices.replaceChildren(...(items.length ? items : [Object.assign(document.createElement("li"),
    { className: "muted", textContent: t("Nothing yet.") })]));
}

function noticeItem(notice) {
  const item = document.createElement("li");
  item.dataset.kind = notice.kind;
  const when = new Date(notice.at).toLocaleTimeString(DATE_LOCALE, { hour: "2-digit", minute: "2-digit" });
  if (notice.kind === "push") {
    item.append(t("{when} · {tutor} sent the class: {title}", { when, tutor: notice.from ?? t("Your tutor"),
      title: notice.title }), " ");
    const link = Object.assign(document.createElement("a"), { href: notice.url, textContent: PUSH_WORDS[notice.what] });
    item.append(link);
    return item;
  }
  item.append(`${when} · ${notice.from ?? t("Your tutor")}: ${notice.text || t("Look here.")}`);
  if (notice.kind === "pointer") {
    item.append(` (x ${notice.x_m} m, y ${notice.y_m} m)`);
    if (boxes) {
      const canvas = document.createElement("canvas");
      canvas.width = 360;
      canvas.height = 240;
      canvas.setAttribute("role", "img");
      canvas.setAttribute("aria-label", t("The lab's map, marked at x {x} m, y {y} m", { x: notice.x_m,
        y: notice.y_m }));
      drawTile(canvas.getContext("2d"), floorPlan(boxes, canvas.width, canvas.height),
        { pose: null, pointer: { x_m: notice.x_m, y_m: notice.y_m } });
      item.append(canvas);
    }
  }
  return item;
}

async function send(method, body) {
  try {
    render(await fetchJson("/api/class-session/hand", { method, body }));
  } catch (error) {
    handLine.textContent = error.message;
  }
}

form.addEventListener("submit", (event) => {
  event.preventDefault();
  send("POST", { text: form.elements.text.value });
  form.elements.text.value = "";
});
lowerButton.addEventListener("click", () => send("DELETE"));

async function start() {
  let seat;
  try {
    seat = await fetchJson("/api/class-session/wall");
  } catch {
    setTimeout(start, 10000);
    return;
  }
  render(seat);
  if (!seat.open) {
    setTimeout(start, 10000);
    return;
  }
  fetchJson(`/api/robots/${encodeURIComponent(seat.robot)}`).then((description) => {
    boxes = description.info?.scene_boxes ?? null;
  }).catch(() => {});
  if (!root.querySelector("chat-panel")) { // the class's chat, beside the tutor's notes: middleware/chat's own room
    registerChatPanel();
    const panel = document.createElement("chat-panel");
    root.querySelector("[data-field=chat]").append(panel);
    connectChat("/ws/class-session", panel);
  }
  channel = new Channel("/ws/class-session/wall");
  channel.addEventListener("message", (event) => {
    const message = parseJsonMessage(event.detail);
    if (message?.type !== "seat") return;
    render(message);
    if (!message.open) {
      channel.close?.();
      setTimeout(start, 10000);
    }
  });
}
start();
