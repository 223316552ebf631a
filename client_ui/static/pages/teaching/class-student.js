// The student's class session page: their own robot's state, and the way to its console once it is ready.
import { fetchJson } from "../../lib/transport.js";

const root = document.getElementById("my-class");
const statusLine = root.querySelector("[data-field=status]");
const consoleLink = root.querySelector("[data-action=console]");

function render(seat) {
  root.dataset.state = seat.open ? seat.state : "none";
  consoleLink.hidden = !seat.console_url;
  if (seat.console_url) consoleLink.href = seat.console_url;
  if (!seat.open) {
    statusLine.textContent = "No class session is open for your courses now. Your tutor starts one in class.";
    return setTimeout(refresh, 10000);
  }
  const course = `${seat.course.code} · ${seat.course.title}`;
  const words = {
    starting: `Class session of ${course}: your robot ${seat.robot} is starting…`,
    ready: `Class session of ${course}: your robot ${seat.robot} is ready.`,
    failed: `Class session of ${course}: your robot did not start. ${seat.message} Tell your tutor.`,
    stopped: `The class session of ${course} has ended.`,
  };
  statusLine.textContent = words[seat.state];
  return setTimeout(refresh, seat.state === "starting" ? 1000 : 5000);
}

async function refresh() {
  try { render(await fetchJson("/api/class-session")); } catch (error) { statusLine.textContent = error.message; }
}

refresh();
