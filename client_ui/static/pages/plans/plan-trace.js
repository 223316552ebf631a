// Pure parts of the plan page: a run's trace from pose samples, its end state in words, the line a feedback
// names, and the distance between two traces' end points. No DOM, so it tests in isolation.

import { t } from "../../lib/i18n.js";


const FINAL = new Set(["succeeded", "aborted", "canceled"]);

/** Whether a goal status is final. */
export function isFinal(status) {
  return FINAL.has(status);
}

/** The trace with a pose sample added (a point once the robot moved 1 cm; at most 5000 points). */
export function addSample(trace, pose, minStep_m = 0.01) {
  if (!pose || !Number.isFinite(pose.x_m) || !Number.isFinite(pose.y_m)) return trace;
  const last = trace[trace.length - 1];
  if (last && Math.hypot(pose.x_m - last.x_m, pose.y_m - last.y_m) < minStep_m) {
    return [...trace.slice(0, -1), { x_m: pose.x_m, y_m: pose.y_m }].slice(-5000);
  }
  return [...trace, { x_m: pose.x_m, y_m: pose.y_m }].slice(-5000);
}

/** The plan line a goal's feedback is at (values.line, else "line N: ..." in its state), or null. */
export function lineOf(feedback) {
  const value = Number(feedback?.values?.line);
  if (Number.isInteger(value) && value > 0) return value;
  const match = /^line (\d+)/.exec(feedback?.state ?? "");
  return match ? Number(match[1]) : null;
}

/** The end of a run in words: "SUCCEEDED", "ABORTED at line 3: ..." or "CANCELED ...". */
export function endStateWords(goal) {
  const status = String(goal?.status ?? "").toUpperCase();
  const message = goal?.message ?? "";
  if (status === "SUCCEEDED") return "SUCCEEDED";
  const line = /^line (\d+)/.exec(message)?.[1] ?? lineOf(goal?.feedback);
  const code = goal?.error_code ? ` (${goal.error_code})` : "";
  const reason = message.replace(/^line \d+:\s*/, "");
  return line ? t("{status} at line {line}{code}: {reason}", { status, line, code, reason }) : `${status}${code}: ${reason}`;
}

/** Distance in centimetres between the last points of two traces, or null while either is empty. */
export function endErrorCm(a, b) {
  const endA = a[a.length - 1];
  const endB = b[b.length - 1];
  if (!endA || !endB) return null;
  return Math.hypot(endA.x_m - endB.x_m, endA.y_m - endB.y_m) * 100;
}
