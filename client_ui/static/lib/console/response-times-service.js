// The response-times panel's feed service ("response-times"): the console's own commands, timed over both legs in
// the wiring's TimingLog (fed by timing-wiring.js from the drive session and the skills' activations), shown every
// half second while the panel is in view, and reported for the tutor's class view.

import { registerFeedService } from "./feed-services.js";
import { reportTimings } from "./timing-report.js";

const TIMINGS_SHOWN_EVERY_MS = 500;

/** Connects a response-times panel to the console's timing log. */
export function connectResponseTimes(wiring, descriptor, panel) {
  const show = (always = false) => {
    const nowMs = performance.now();
    wiring.timings.expire(nowMs);
    if (always || wiring.layout.isShown(descriptor.id)) panel.report = { log: wiring.timings, nowMs };
  };
  wiring.onStart(() => {
    show(true);
    setInterval(show, TIMINGS_SHOWN_EVERY_MS);
    reportTimings(wiring.timings, wiring.robotName); // for the tutor's class view
  });
}

registerFeedService("response-times", connectResponseTimes);
