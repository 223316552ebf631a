// Connects a camera panel's feedback layer to the person's saved choice (on by default); the robot's
// description and the drive session's messages reach the panel through the console wiring.

import { fetchJson } from "../transport.js";

export const FEEDBACK_PREFERENCE = "/api/me/preferences/camera-feedback";
export const FILL_PREFERENCE = "/api/me/preferences/camera-feedback-fill";
// The picture this person chose per robot kind, {"<kind>": "video" | "drawn"}: kept with the account, so that
// their other browsers (the lab's PC, their phone) open with it too. The page gets it with the panel descriptor.
export const PICTURE_PREFERENCE = "/api/me/preferences/camera-picture";

function save(url, value, panel) {
  fetchJson(url, { method: "PUT", body: { value } }).catch((error) => {
    if (error.code === "preference_locked" && panel) { // a delay trial began meanwhile: its setting holds
      panel.feedbackEnabled = !value;
      panel.feedbackLocked = error.message;
      return;
    }
    console.warn("the motion preview choice was not saved:", error.message);
  });
}

/** The saved on/off choice, and whether a delay trial holds it (it sets the preview until it ends). */
function loadPreview(panel) {
  fetchJson(FEEDBACK_PREFERENCE)
    .then((answer) => {
      if (typeof answer?.value === "boolean") panel.feedbackEnabled = answer.value;
      panel.feedbackLocked = answer?.locked ?? null;
    })
    .catch(() => {}); // no saved choice: the layer stays on
}

/** Loads and saves this user's "motion preview" choices (on/off, fill). */
export function bindFeedback(panel) {
  loadPreview(panel);
  // A delay trial begun or ended while this console is open changes the added delay: read the choice again.
  panel.addEventListener("camera-injected-delay-change", () => loadPreview(panel));
  fetchJson(FILL_PREFERENCE)
    .then((answer) => { if (typeof answer?.value === "string") panel.feedbackFill = answer.value; })
    .catch(() => {}); // no saved choice: the edges are continued
  panel.addEventListener("camera-feedback-change", ({ detail }) => save(FEEDBACK_PREFERENCE, Boolean(detail.enabled), panel));
  panel.addEventListener("camera-feedback-fill-change", ({ detail }) => save(FILL_PREFERENCE, String(detail.fill)));
}

/** Saves source ("video" | "drawn") as this person's picture for robots of kind, keeping their other kinds' choices. */
export async function savePictureChoice(kind, source) {
  try {
    const stored = (await fetchJson(PICTURE_PREFERENCE))?.value;
    const choices = stored && typeof stored === "object" && !Array.isArray(stored) ? stored : {};
    await fetchJson(PICTURE_PREFERENCE, { method: "PUT", body: { value: { ...choices, [kind]: source } } });
  } catch (error) {
    console.warn("the picture choice was not saved:", error.message); // it still holds on this page
  }
}
