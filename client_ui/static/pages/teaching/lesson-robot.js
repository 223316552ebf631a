// The robot a lesson drives, beside the video: its camera and lab model (the console's own panels). Another
// robot chosen in the list opens the page again for it (after the video's pause has stopped the first one), so
// no stream of the robot left behind stays open. The practice robot is shown once it runs; the page offers to
// start it.
import { h } from "../../lib/dom.js";
import { fetchJson } from "../../lib/transport.js";
import { showRobotPanels } from "../../lib/console/robot-panels.js";

const LESSON_PANELS = ["camera", "map"];

async function showPractice(host) {
  const state = await fetchJson("/api/practice");
  if (state.running) {
    await showRobotPanels(host, state.name, LESSON_PANELS);
    return;
  }
  const problem = h("p", { role: "alert" });
  const start = h("button", { type: "button", class: "button button--primary", text: "Start my practice robot",
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
  host.replaceChildren(h("p", { text: "Your practice robot is off. Start it to see it here and let the lesson drive it." }),
    start, problem);
}

/** Show the robot chosen in `select` (the page's ?robot= when it names one) in host; follow later choices. */
export function showLessonRobot(host, select, video) {
  const asked = new URLSearchParams(window.location.search).get("robot");
  if (asked && [...select.options].some((option) => option.value === asked)) select.value = asked;
  const reopen = () => {
    const url = new URL(window.location.href);
    url.searchParams.set("robot", select.value);
    window.location.assign(url);
  };
  select.addEventListener("change", () => {
    if (video.paused) reopen();
    else {
      video.addEventListener("pause", () => setTimeout(reopen, 0), { once: true });
      video.pause();
    }
  });
  const shown = select.value === "practice" ? showPractice(host) : showRobotPanels(host, select.value, LESSON_PANELS);
  shown.catch((error) => host.replaceChildren(h("p", { role: "alert", text: error.message })));
}
