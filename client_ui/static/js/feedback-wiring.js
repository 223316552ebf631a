// Connects a camera panel's feedback layer to the person's saved choice (on by default) and to the robot's
// description; the drive session's messages reach the panel through the console wiring.

import { fetchJson } from "./transport.js";

export const FEEDBACK_PREFERENCE = "/api/me/preferences/camera-feedback";

/** Loads and saves the "motion preview" choice of this user; passes RobotInfo to the panel. */
export function bindFeedback(panel, onInfo) {
  onInfo((info) => { panel.info = info; });
  fetchJson(FEEDBACK_PREFERENCE)
    .then((answer) => { if (typeof answer?.value === "boolean") panel.feedbackEnabled = answer.value; })
    .catch(() => {}); // no saved choice: the layer stays on
  panel.addEventListener("camera-feedback-change", ({ detail }) => {
    fetchJson(FEEDBACK_PREFERENCE, { method: "PUT", body: { value: Boolean(detail.enabled) } }).catch((error) => {
      console.warn("the motion preview choice was not saved:", error.message);
    });
  });
}
