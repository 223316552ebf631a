// The tutor's class wall: every student's robot drawn from the one wall socket's poses, their hands, and the
// tutor's actions on one robot or on all. The server decides every action; this page shows and asks.
import { Channel, fetchJson, parseJsonMessage } from "../../lib/transport.js";
import { canvasToWorld, moveCursor, sceneBounds } from "../../lib/map-geometry.js";
import { t } from "../../lib/i18n.js";
import { connectChat } from "../../lib/console/chat-session.js";
import { register as registerChatPanel } from "../../panels/chat-panel/chat-panel.js";
import { drawTile, floorPlan, grow, parsePoseRow, tileState } from "./class-wall-draw.js";

const root = document.getElementById("class-wall");
const api = `/api/courses/${root.dataset.courseId}/class-wall`;
const list = root.querySelector("[data-field=tiles]");
const template = document.getElementById("wall-tile");
const summary = root.querySelector("[data-field=summary]");
const outcome = root.querySelector("[data-field=outcome]"); // what the tutor's last action did
const errorLine = root.querySelector("[data-field=error]");
const pushForm = root.querySelector("[data-field=push]");
const pushSelect = pushForm.querySelector("select");
const filters = [...root.querySelectorAll("[data-filter]")];
const STATE_WORDS = {
  idle: t("idle"), driving: t("driving"), skill: t("running a skill"), plan: t("running a plan"),
  test: t("taking a test"), faulted: t("faulted"), starting: t("starting…"),
};
const PUSH_WORDS = { lesson: t("Lesson"), exercise: t("Exercise"), plan: t("Plan"), test: t("Test") };
const tiles = new Map(); // user id -> tile
const plans = new Map(); // "<w>x<h>" -> floor plan bitmap and view
let boxes = null;
let boxesAsked = false;
let frameAsked = false;
let lastSeats = [];

function showError(error) {
  errorLine.textContent = error.message;
  errorLine.hidden = !error.message;
}

function planFor(canvas) {
  const key = `${canvas.width}x${canvas.height}`;
  if (!plans.has(key)) plans.set(key, floorPlan(boxes ?? [], canvas.width, canvas.height));
  return plans.get(key);
}

const visibility = new IntersectionObserver((entries) => {
  for (const entry of entries) {
    const tile = tiles.get(Number(entry.target.dataset.userId));
    if (!tile) continue;
    tile.visible = entry.isIntersecting;
    if (tile.visible) markDirty(tile);
  }
});

function markDirty(tile) {
  tile.dirty = true;
  if (!frameAsked) {
    frameAsked = true;
    requestAnimationFrame(drawDirty);
  }
}

function drawDirty() {
  frameAsked = false;
  for (const tile of tiles.values()) {
    if (!tile.dirty || !tile.visible || tile.canvas.offsetParent === null) continue;
    tile.dirty = false;
    drawTile(tile.ctx, planFor(tile.canvas), {
      pose: tile.pose, trail: tile.trail, state: tile.state, pointer: tile.pointer,
    });
  }
}

function point(tile, x_m, y_m) {
  tile.pointer = { x_m: Math.round(x_m * 100) / 100, y_m: Math.round(y_m * 100) / 100 };
  tile.element.querySelector("[data-field=point-help]").textContent =
    t("Pointing at x {x} m, y {y} m (click or use the arrow keys on the map to move it).",
      { x: tile.pointer.x_m, y: tile.pointer.y_m });
  markDirty(tile);
}

function makeTile(seat) {
  const element = template.content.firstElementChild.cloneNode(true);
  element.dataset.userId = seat.user_id;
  const canvas = element.querySelector("canvas");
  const scale = Math.min(2, window.devicePixelRatio || 1);
  canvas.width = Math.round(180 * scale);
  canvas.height = Math.round(120 * scale);
  const tile = {
    seat, element, canvas, ctx: canvas.getContext("2d"), pose: null, trail: [], state: "idle", pointer: null,
    dirty: true, visible: false, words: null, battery: null,
    fields: { state: element.querySelector("[data-field=state]"), battery: element.querySelector("[data-field=battery]") },
  };
  canvas.addEventListener("click", (event) => { // a pointer for the note, while Assist is open
    if (!element.querySelector("details").open || !boxes) return;
    const plan = planFor(canvas);
    const box = canvas.getBoundingClientRect();
    const [x_m, y_m] = canvasToWorld(plan.view, (event.clientX - box.left) * (canvas.width / box.width),
      (event.clientY - box.top) * (canvas.height / box.height));
    point(tile, x_m, y_m);
  });
  canvas.addEventListener("keydown", (event) => { // the same by keyboard: arrows move the pointer 10 cm
    const step = { ArrowLeft: [-0.1, 0], ArrowRight: [0.1, 0], ArrowUp: [0, 0.1], ArrowDown: [0, -0.1] }[event.key];
    if (!step || !element.querySelector("details").open) return;
    event.preventDefault();
    const from = tile.pointer ?? tile.pose ?? { x_m: 0, y_m: 0 };
    const [x_m, y_m] = moveCursor([from.x_m, from.y_m], step[0], step[1], sceneBounds(boxes ?? []));
    point(tile, x_m, y_m);
  });
  element.querySelector("details").addEventListener("toggle", (event) => { // the map takes keys while Assist is open
    canvas.tabIndex = event.target.open ? 0 : -1;
    canvas.setAttribute("aria-hidden", String(!event.target.open));
    canvas.setAttribute("aria-label", t("Map of {name}'s robot: arrow keys move the pointer for your note.",
      { name: tile.seat.username }));
  });
  tiles.set(seat.user_id, tile);
  visibility.observe(element);
  return tile;
}

/** The tile's state and battery words, written only when they change (a pose comes 5 times a second per tile). */
function renderWords(tile) {
  const { seat, element } = tile;
  tile.state = tileState(seat, tile.pose);
  const activity = tile.pose?.activity ?? "";
  const detail = (tile.state === "skill" || tile.state === "plan") ? ` (${activity.split(":").slice(1).join(":")})` : "";
  const words = STATE_WORDS[tile.state] + detail + (tile.state === "faulted" && seat.message ? `: ${seat.message}` : "");
  const charge = tile.pose?.charge;
  const battery = Number.isFinite(charge) ? t("battery {percent} %", { percent: Math.round(charge * 100) })
    : t("battery unknown");
  if (words !== tile.words) {
    tile.words = words;
    element.dataset.state = tile.state;
    tile.fields.state.textContent = words;
    applyFilter(tile);
  }
  if (battery !== tile.battery) {
    tile.battery = battery;
    tile.fields.battery.textContent = battery;
  }
}

function renderTile(tile) {
  const { seat, element } = tile;
  renderWords(tile);
  element.dataset.hand = String(Boolean(seat.hand));
  element.dataset.held = String(Boolean(seat.held_by));
  element.querySelector("[data-field=name]").textContent = seat.username;
  const hand = element.querySelector("[data-field=hand]");
  hand.hidden = !seat.hand;
  hand.textContent = !seat.hand ? "" : seat.hand.text ? t("Hand raised: {text}", { text: seat.hand.text })
    : t("Hand raised.");
  const held = element.querySelector("[data-field=held]");
  held.hidden = !seat.held_by;
  held.textContent = seat.held_by ? t("Taken over by {tutor}", { tutor: seat.held_by }) : "";
  element.querySelector("[data-action=watch]").href = seat.watch_url ?? `/lab/${seat.robot}`;
  element.querySelector("[data-action=watch]").setAttribute("aria-label",
    t("Watch {name}'s console", { name: seat.username }));
  element.querySelector("[data-action=take_over]").hidden = Boolean(seat.held_by);
  element.querySelector("[data-action=give_back]").hidden = !seat.held_by;
  element.querySelector("[data-action=answer]").hidden = !seat.hand;
  for (const button of element.querySelectorAll("button[data-action]")) {
    button.setAttribute("aria-label", `${button.textContent.trim()}: ${seat.username}`);
  }
  applyFilter(tile);
}

function applyFilter(tile) {
  const wanted = filters.filter((box) => box.checked).map((box) => box.dataset.filter);
  tile.element.hidden = wanted.length > 0 && !wanted.some((filter) =>
    (filter === "hand" ? Boolean(tile.seat.hand) : tile.state === filter));
}

function renderSummary() {
  const states = [...tiles.values()].map((tile) => tile.state);
  const hands = lastSeats.filter((seat) => seat.hand).length;
  const faulted = states.filter((state) => state === "faulted").length;
  const moving = states.filter((state) => state !== "idle" && state !== "faulted").length;
  const words = t("{count} students: {busy} busy, {hands} with a hand raised, {faulted} faulted.",
    { count: lastSeats.length, busy: moving, hands, faulted });
  if (summary.textContent !== words) summary.textContent = words; // a live region: only a change is announced
  root.dataset.hands = String(hands);
}

/** The tiles in the seats' order, moved only when it changed: moving an element takes the focus from whatever the
 * tutor is using in it (the map's pointer keys, the note being typed), and seats come at every hand or state. */
function placeInOrder(ordered) {
  const current = list.children;
  if (current.length === ordered.length && ordered.every((element, i) => current[i] === element)) return;
  const focused = document.activeElement;
  list.replaceChildren(...ordered);
  if (focused instanceof HTMLElement && focused !== document.activeElement && list.contains(focused)) {
    focused.focus({ preventScroll: true });
  }
}

function updateSeats(seats) {
  lastSeats = seats;
  const seen = new Set();
  const ordered = [];
  for (const seat of seats) {
    seen.add(seat.user_id);
    const tile = tiles.get(seat.user_id) ?? makeTile(seat);
    tile.seat = { ...tile.seat, ...seat };
    renderTile(tile);
    ordered.push(tile.element);
  }
  for (const [userId, tile] of tiles) {
    if (!seen.has(userId)) {
      visibility.unobserve(tile.element);
      tiles.delete(userId);
    }
  }
  placeInOrder(ordered);
  renderSummary();
  askForScene(seats);
}

async function askForScene(seats) {
  const ready = seats.find((seat) => seat.seat_state === "ready");
  if (boxesAsked || !ready) return;
  boxesAsked = true;
  try {
    const description = await fetchJson(`/api/robots/${encodeURIComponent(ready.robot)}`);
    boxes = description.info?.scene_boxes ?? [];
    plans.clear();
    for (const tile of tiles.values()) markDirty(tile);
  } catch (error) {
    boxesAsked = false; // the robot is not answering yet: the next seats message asks again
  }
}

let posesSeen = 0;
function updatePoses(rows) {
  posesSeen += 1;
  for (const row of rows) {
    const pose = parsePoseRow(row);
    const tile = tiles.get(pose.userId);
    if (!tile) continue;
    tile.pose = pose;
    grow(tile.trail, pose);
    tile.element.dataset.pose = `${pose.x_m.toFixed(2)},${pose.y_m.toFixed(2)},${pose.theta_rad.toFixed(2)}`; // data, not text: a data attribute
    renderWords(tile);
    markDirty(tile);
  }
  if (posesSeen % 5 === 0) renderSummary();
}

const channel = new Channel(`/ws/courses/${root.dataset.courseId}/class-wall`);
channel.addEventListener("message", (event) => {
  const message = parseJsonMessage(event.detail);
  if (message?.type === "seats") updateSeats(message.seats);
  else if (message?.type === "poses") updatePoses(message.robots);
  else if (message?.type === "ended") summary.textContent = t("The class session has ended.");
  else if (message?.type === "error") showError(message);
});

async function act(url, body, button) {
  if (button) button.disabled = true;
  showError({ message: "" });
  try {
    return await fetchJson(url, { method: "POST", body });
  } catch (error) {
    showError(error);
    return null;
  } finally {
    if (button) button.disabled = false;
  }
}

list.addEventListener("click", async (event) => {
  const button = event.target.closest("button[data-action]");
  if (!button) return;
  const tile = tiles.get(Number(button.closest("[data-user-id]").dataset.userId));
  const action = button.dataset.action;
  const done = await act(`${api}/seats/${tile.seat.user_id}`, { action }, button);
  if (!done) return;
  const name = tile.seat.username;
  const words = {
    stop: t("{name}'s robot stopped.", { name }), dock: t("{name}'s robot is back at its dock.", { name }),
    take_over: t("You hold {name}'s robot: Watch to drive it; Give back returns it.", { name }),
    give_back: t("{name} has their robot back.", { name }), answer: t("{name}'s hand is down.", { name }),
  };
  outcome.textContent = words[action] ?? "";
});

list.addEventListener("submit", async (event) => {
  event.preventDefault();
  const form = event.target;
  const tile = tiles.get(Number(form.closest("[data-user-id]").dataset.userId));
  const body = { action: "note", text: form.elements.text.value };
  if (tile.pointer) body.point = tile.pointer;
  if (await act(`${api}/seats/${tile.seat.user_id}`, body, form.querySelector("button"))) {
    form.reset();
    outcome.textContent = t("Note sent to {name}.", { name: tile.seat.username });
    tile.pointer = null;
    form.querySelector("[data-field=point-help]").textContent = t("Click the map, or use the arrow keys on it, to point at a place (optional).");
    markDirty(tile);
  }
});

for (const button of root.querySelectorAll(".wall-toolbar > button[data-action]")) {
  button.addEventListener("click", async () => {
    const done = await act(api, { action: button.dataset.action }, button);
    if (!done) return;
    const refused = Object.entries(done.refused).map(([robot, why]) => `${robot} (${why})`).join(", ");
    const doneWords = button.dataset.action === "stop_all" ? t("{count} robots stopped.", { count: done.done })
      : t("{count} robots sent to their docks.", { count: done.done });
    outcome.textContent = refused ? `${doneWords} ${t("Not: {robots}.", { robots: refused })}` : doneWords;
  });
}

pushForm.addEventListener("submit", async (event) => {
  event.preventDefault();
  const [kind, id] = pushSelect.value.split(":");
  if (!id) return;
  const done = await act(api, { action: "push", kind, id: Number(id) }, pushForm.querySelector("button"));
  if (done) outcome.textContent = t("Sent to every student: {title}.", { title: done.title });
});

for (const box of filters) box.addEventListener("change", () => tiles.forEach(applyFilter));

// The class's chat (middleware/chat's room of the class), opened only when the tutor opens it.
const chatBox = document.querySelector("[data-field=chat-box]");
chatBox.addEventListener("toggle", () => {
  if (!chatBox.open || chatBox.querySelector("chat-panel")) return;
  registerChatPanel();
  const panel = document.createElement("chat-panel");
  chatBox.querySelector("[data-field=chat]").append(panel);
  connectChat(`/ws/courses/${root.dataset.courseId}/class-wall`, panel);
});

async function load() {
  try {
    const wall = await fetchJson(api);
    const options = [];
    for (const [kind, items] of Object.entries(wall.choices)) {
      const group = document.createElement("optgroup");
      group.label = PUSH_WORDS[kind];
      for (const item of items) group.append(new Option(item.title, `${kind}:${item.id}`));
      if (items.length) options.push(group);
    }
    pushSelect.replaceChildren(...options);
    pushForm.hidden = !options.length;
    updateSeats(wall.seats);
  } catch (error) {
    showError(error);
    summary.textContent = error.code === "no_class_session" ? t("No class session is open: start one first.") : "";
  }
}
load();
