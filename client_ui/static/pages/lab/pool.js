// Waiting for any robot of a kind: keeps the place in the pool's queue with a join every few seconds, says the
// position and the expected wait, and opens the console of the robot bound to this user.
import { fetchJson } from "../../lib/transport.js";

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
  if (seconds < 60) return "less than a minute";
  const whole = Math.round(seconds / 60);
  return whole === 1 ? "about 1 minute" : `about ${whole} minutes`;
}

function render(seat) {
  root.dataset.state = seat.robot_name ? "bound" : seat.position > 0 ? "waiting" : "idle";
  if (seat.robot_name) {
    statusLine.textContent = `${seat.robot_name} is yours now. Opening its console…`;
    waitLine.textContent = "";
    consoleLink.href = seat.console_url;
    consoleLink.textContent = `Open ${seat.robot_name}'s console`;
    consoleLink.hidden = false;
    leaveButton.hidden = true;
    window.location.assign(seat.console_url);
    return;
  }
  statusLine.textContent = `You are number ${seat.position} of ${seat.queue_size} waiting for a ${kind} robot.`;
  waitLine.textContent = seat.estimated_wait_s === null
    ? "No robot of this kind answers now, so no turn can start; you keep your place."
    : `Expected wait: ${minutes(seat.estimated_wait_s)} (${seat.robots} robots serve this queue).`;
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
  statusLine.textContent = "You left the queue.";
  waitLine.textContent = "";
  leaveButton.hidden = true;
});

keep();
