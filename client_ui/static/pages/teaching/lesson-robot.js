// The robot a lesson drives, beside the video: its camera and lab model (the console's own panels), and on request
// its raw readings. Another
// robot chosen in the list opens the page again for it (after the video's pause has stopped the first one), so
// no stream of the robot left behind stays open. The practice robot is shown once it runs; the page offers to
// start it.
import { h } from "../../lib/dom.js";
import { fetchJson } from "../../lib/transport.js";
import { showRobotPanels } from "../../lib/console/robot-panels.js";
import { t } from "../../lib/i18n.js";

const LESSON_PANELS = ["camera", "map"];
// The raw readings the 2022 paper showed beside its video, as the console's plots: odometry (a time plot of the
// speeds), sonar and laser (polar plots). Shown when the learner asks (?readings=1).
const READING_PANELS = ["odometry", "sonar", "laser"];
let panelsWanted = LESSON_PANELS;

async function showPractice(host) {
  const state = await fetchJson("/api/practice");
  if (state.running) {
    await showRobotPanels(host, state.name, panelsWanted);
    return;
  }
  const problem = h("p", { role: "alert" });
  const start = h("button", { type: "button", class: "button button--primary", text: t("Start my practice robot"),
    onclick: async () => {
      start.disabled = true;
      try {
        await fetchJson("/api/practice", { method: "POST" });
        await showPractice(host);
      } catch (error) {
        problem.textContent = error.message;
        start.disabled = false;
      }
    } });
  host.replaceChildren(h("p", { text: t("Your practice robot is off. Start it to see it here and let the lesson drive it.") }),
    start, problem);
}

/** Show the robot chosen in `select` (the page's ?robot= when it names one) in host, with its raw readings when
 * `readings` is checked (?readings=1); follow later choices. */
export function showLessonRobot(host, select, video, readings) {
  const query = new URLSearchParams(window.location.search);
  const asked = query.get("robot");
  if (asked && [...select.options].some((option) => option.value === asked)) select.value = asked;
  readings.checked = query.get("readings") === "1";
  panelsWanted = readings.checked ? [...LESSON_PANELS, ...READING_PANELS] : LESSON_PANELS;
  const reopen = () => {
    const url = new URL(window.location.href);
    url.searchParams.set("robot", select.value);
    if (readings.checked) url.searchParams.set("readings", "1");
    else url.searchParams.delete("readings");
    window.location.assign(url);
  };
  const reopenPaused = () => {
    if (video.paused) reopen();
    else {
      video.addEventListener("pause", () => setTimeout(reopen, 0), { once: true });
      video.pause();
    }
  };
  select.addEventListener("change", reopenPaused);
  readings.addEventListener("change", reopenPaused);
  const shown = select.value === "practice" ? showPractice(host) : showRobotPanels(host, select.value, panelsWanted);
  shown.catch((error) => host.replaceChildren(h("p", { role: "alert", text: error.message })));
}
