// Feeds the console's TimingLog (lib/response-times.js) from the commands it really sends: each drive command on
// the drive session, answered by its ack (or, in order, by an error), and each skill activation's request.

import { ApiError } from "../transport.js";

let activations = 0;

/** Times every drive command of session in log; a new connection counts what its predecessor left unanswered. */
export function timeDriveCommands(session, log) {
  session.addEventListener("ready", () => log.expire(performance.now(), "drive"));
  session.addEventListener("sent", ({ detail }) => {
    log.sent("drive", detail.sequence, performance.now(), JSON.stringify(detail).length);
  });
  session.addEventListener("ack", ({ detail }) => {
    const now = performance.now();
    if (detail.superseded > 0) log.supersededBefore("drive", detail.sequence, now);
    log.answered("drive", detail.sequence, now,
      { robotMs: Number(detail.robot_rtt_ms ?? NaN), bytes: JSON.stringify(detail).length });
  });
  // A refused or invalid command is answered without a sequence: the socket keeps order, so it answers the oldest.
  session.addEventListener("error", ({ detail }) => {
    log.answeredOldest("drive", performance.now(), { bytes: JSON.stringify(detail).length });
  });
}

/** request() (a fetch of a skill activation, whose body is body) timed in log; its answer, or what it throws. */
export async function timeActivation(log, body, request) {
  const id = ++activations;
  log.sent("skill", id, performance.now(), JSON.stringify(body ?? {}).length);
  try {
    const answer = await request();
    log.answered("skill", id, performance.now(),
      { robotMs: Number(answer?.robot_rtt_ms ?? NaN), bytes: JSON.stringify(answer ?? {}).length });
    return answer;
  } catch (error) {
    if (error instanceof ApiError && error.status > 0) log.answered("skill", id, performance.now(), { timed: false });
    else log.lost("skill", id);
    throw error;
  }
}
