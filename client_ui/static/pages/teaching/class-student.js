// The student's class session page: their own robot's state, and the way to its console once it is ready.
import { fetchJson } from "../../lib/transport.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("my-class");
const statusLine = root.querySelector("[data-field=status]");
const consoleLink = root.querySelector("[data-action=console]");
const restartButton = root.querySelector("[data-action=restart]");
let timer = null;

function render(seat) {
  root.dataset.state = seat.open ? seat.state : "none";
  clearTimeout(timer);
  consoleLink.hidden = !seat.console_url;
  restartButton.hidden = !(seat.open && (seat.state === "stopped" || seat.state === "failed"));
  if (seat.console_url) consoleLink.href = seat.console_url;
  if (!seat.open) {
    statusLine.textContent = t("No class session is open for your courses now. Your tutor starts one in class.");
    timer = setTimeout(refresh, 10000);
    return;
  }
  const course = `${seat.course.code} · ${seat.course.title}`;
  const words = {
    starting: t("Class session of {course}: your robot {robot} is starting…", { course, robot: seat.robot }),
    ready: t("Class session of {course}: your robot {robot} is ready.", { course, robot: seat.robot }),
    failed: t("Class session of {course}: your robot did not start. {message} Tell your tutor.", { course, message: seat.message }),
    stopped: t("Class session of {course}: your robot {robot} is stopped. Start it again to go on.", { course, robot: seat.robot }),
  };
  statusLine.textContent = words[seat.state];
  timer = setTimeout(refresh, seat.state === "starting" ? 1000 : 5000);
}

restartButton.addEventListener("click", async () => {
  restartButton.disabled = true;
  try { render(await fetchJson("/api/class-session/robot", { method: "POST" })); } catch (error) {
    statusLine.textContent = error.message;
  } finally {
    restartButton.disabled = false;
  }
});

async function refresh() {
  try { render(await fetchJson("/api/class-session")); } catch (error) { statusLine.textContent = error.message; }
}

refresh();
