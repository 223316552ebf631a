// Waiting for any robot of a kind: keeps the place in the pool's queue with a join every few seconds, says the
// position and the expected wait, and opens the console of the robot bound to this user.
import { fetchJson } from "../../lib/transport.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("pool");
const kind = root.dataset.kind;
const statusLine = root.querySelector("[data-field=status]");
const waitLine = root.querySelector("[data-field=wait]");
const consoleLink = root.querySelector("[data-action=console]");
const leaveButton = root.querySelector("[data-action=leave]");
const api = `/api/pools/${encodeURIComponent(kind)}/queue`;
let timer = null;
let left = false;

function minutes(seconds) {
  if (seconds < 60) return t("less than a minute");
  const whole = Math.round(seconds / 60);
  return whole === 1 ? t("about 1 minute") : t("about {whole} minutes", { whole });
}

function render(seat) {
  root.dataset.state = seat.robot_name ? "bound" : seat.position > 0 ? "waiting" : "idle";
  if (seat.robot_name) {
    statusLine.textContent = t("{robot_name} is yours now. Opening its console…", { robot_name: seat.robot_name });
    waitLine.textContent = "";
    consoleLink.href = seat.console_url;
    consoleLink.textContent = t("Open {robot_name}'s console", { robot_name: seat.robot_name });
    consoleLink.hidden = false;
    leaveButton.hidden = true;
    window.location.assign(seat.console_url);
    return;
  }
  statusLine.textContent = t("You are number {position} of {queue_size} waiting for a {kind} robot.", { position: seat.position, queue_size: seat.queue_size, kind });
  waitLine.textContent = seat.estimated_wait_s === null
    ? t("No robot of this kind answers now, so no turn can start; you keep your place.")
    : t("Expected wait: {estimated_wait_s} ({robots} robots serve this queue).", { estimated_wait_s: minutes(seat.estimated_wait_s), robots: seat.robots });
  timer = setTimeout(keep, 2000);
}

async function keep() {
  if (left) return;
  try {
    render(await fetchJson(api, { method: "POST" }));
  } catch (error) {
    statusLine.textContent = error.message;
    timer = setTimeout(keep, 5000);
  }
}

leaveButton.addEventListener("click", async () => {
  left = true;
  clearTimeout(timer);
  try { await fetchJson(api, { method: "DELETE" }); } catch (error) { /* the grace period ends the wait anyway */ }
  statusLine.textContent = t("You left the queue.");
  waitLine.textContent = "";
  leaveButton.hidden = true;
});

keep();
