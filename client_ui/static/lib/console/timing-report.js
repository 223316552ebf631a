// Reports the console's response-time figures (lib/response-times.js reportOf) to the middleware now and then, so
// the student's tutor reads them in the class view; the panel never depends on it.

import { reportOf } from "../response-times.js";
import { fetchJson } from "../transport.js";

const REPORT_EVERY_MS = 10000;

/** Every REPORT_EVERY_MS, log's figures for robotName when commands were sent since the last report; a failed
 *  report waits for the next, which carries the same figures and more. */
export function reportTimings(log, robotName) {
  let reportedSent = 0;
  return setInterval(async () => {
    const { sent } = log.delivery();
    if (sent === reportedSent) return;
    try {
      await fetchJson(`/api/robots/${encodeURIComponent(robotName)}/response-times`,
        { method: "PUT", body: reportOf(log, performance.now()) });
      reportedSent = sent;
    } catch {
      // the next report tries again
    }
  }, REPORT_EVERY_MS);
}
