// The tutor's class session page: start it, follow every student's robot as it starts, end it.
import { fetchJson } from "../../lib/transport.js";
import { responseTimesCell } from "./class-response-times.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("class-session");
const api = `/api/courses/${root.dataset.courseId}/class-session`;
const summary = root.querySelector("[data-field=summary]");
const errorLine = root.querySelector("[data-field=error]");
const startButton = root.querySelector("[data-action=start]");
const endButton = root.querySelector("[data-action=end]");
const sceneChoice = root.querySelector("[data-field=scene-choice]");
const sceneSelect = sceneChoice.querySelector("select");
const table = root.querySelector("table");
const rows = table.querySelector("tbody");
const STATE_WORDS = { starting: t("starting…"), ready: t("ready"), failed: t("did not start"), stopped: t("stopped") };
let timer = null;
const legsOpen = new Set(); // user ids whose response-time legs the tutor opened

function seatRow(seat) {
  const row = document.createElement("tr");
  row.dataset.state = seat.state;
  for (const [label, text] of [[t("Student"), seat.username], [t("Robot"), seat.robot],
    [t("State"), STATE_WORDS[seat.state] + (seat.message ? `: ${seat.message}` : "")]]) {
    const cell = document.createElement("td");
    cell.dataset.label = label;
    cell.textContent = text;
    row.append(cell);
  }
  const times = document.createElement("td");
  times.dataset.label = t("Response times");
  times.dataset.field = "response-times";
  times.append(...responseTimesCell(seat.response_times));
  const legs = times.querySelector("details");
  if (legs) { // the page refreshes every few seconds: a tutor's open "Legs" stays open
    legs.open = legsOpen.has(seat.user_id);
    legs.addEventListener("toggle", () => (legs.open ? legsOpen.add(seat.user_id) : legsOpen.delete(seat.user_id)));
  }
  row.append(times);
  return row;
}

function render(state) {
  root.dataset.open = String(state.open);
  startButton.hidden = state.open;
  sceneChoice.hidden = state.open;
  endButton.hidden = !state.open;
  root.querySelector("[data-action=wall]").hidden = !state.open;
  table.hidden = !state.open;
  rows.replaceChildren(...state.seats.map(seatRow));
  const { starting, ready, failed, stopped } = state.counts;
  summary.textContent = state.open
    ? t("Class session open ({scene}): {ready} of {length} robots ready", { scene: state.scene, ready, length: state.seats.length })
      + (starting ? t(", {starting} starting", { starting }) : "") + (failed ? t(", {failed} did not start", { failed }) : "")
      + (stopped ? t(", {stopped} stopped", { stopped }) : "") + "."
    : t("No class session is open for this course.");
  clearTimeout(timer);
  if (state.open) timer = setTimeout(refresh, starting ? 1000 : 5000);
}

function showError(error) {
  errorLine.textContent = error.message;
  errorLine.hidden = false;
}

async function refresh() {
  try { render(await fetchJson(api)); } catch (error) { showError(error); }
}

async function act(method) {
  startButton.disabled = endButton.disabled = true;
  errorLine.hidden = true;
  summary.textContent = method === "POST" ? t("Starting every student's robot…") : t("Stopping every robot…");
  try {
    render(await fetchJson(api, method === "POST" ? { method, body: { scene: sceneSelect.value } } : { method }));
  } catch (error) {
    showError(error);
    await refresh();
  } finally {
    startButton.disabled = endButton.disabled = false;
  }
}

startButton.addEventListener("click", () => act("POST"));
endButton.addEventListener("click", () => {
  if (window.confirm(t("End the class session? Every student's robot stops."))) act("DELETE");
});
refresh();
