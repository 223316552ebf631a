// The camera's feedback layer: draws the last frame moved by the commands it does not show yet, and the
// predicted path on the floor. All maths is in feedback-math.js; here it becomes setTransform and drawImage
// calls (GPU-friendly; no per-pixel loop).

import {
  CommandLog, cameraModel, edgeFillRects, isWarped, predictedPathPoints, referenceDepthFromScan, warpTransform,
} from "../../lib/feedback-math.js";

const IDLE_EPSILON = 1e-4;

/**
 * What fills the part of the view the frame does not cover: "edges" continues the picture's edge pixels
 * outwards (closer to what the camera will show than black, in benchmarks.feedback) and outlines the real
 * picture; "black" is the thesis's algorithm 3.1.
 */
export const FILL_MODES = Object.freeze(["edges", "black"]);

/** Draws bitmap over the whole canvas moved by transform, the uncovered part filled as `fill` says. */
export function drawWarped(ctx, bitmap, transform, fill = "edges") {
  const { width, height } = ctx.canvas;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  if (!isWarped(transform)) {
    ctx.drawImage(bitmap, 0, 0, width, height);
    return;
  }
  if (fill === "black") {
    ctx.fillStyle = "#000";
    ctx.fillRect(0, 0, width, height);
  } else {
    for (const rect of edgeFillRects(transform, bitmap, { width, height })) ctx.drawImage(bitmap, ...rect);
  }
  ctx.setTransform(transform.scale, 0, 0, transform.scale, transform.tx, transform.ty);
  ctx.drawImage(bitmap, 0, 0, width, height);
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  if (fill !== "black") {
    // The continued edges are a guess: a thin dashed outline shows where the real picture ends.
    ctx.save();
    ctx.strokeStyle = "rgba(255, 255, 255, 0.6)";
    ctx.lineWidth = 1;
    ctx.setLineDash([4, 4]);
    ctx.strokeRect(transform.tx + 0.5, transform.ty + 0.5, transform.scale * width - 1, transform.scale * height - 1);
    ctx.restore();
  }
}

export class FeedbackLayer {
  enabled = true;
  fill = FILL_MODES[0];
  log = new CommandLog();
  #info = {};
  #depthM = NaN;
  #lastTransform = null;

  setInfo(info) {
    if (!info || typeof info !== "object") return;
    this.#info = {
      hfovDeg: Number(info.camera_hfov_deg) || undefined,
      width: Number(info.camera_width_px) || undefined,
      height: Number(info.camera_height_px) || undefined,
    };
  }

  /** The newest laser scan ({angle_min_rad, angle_increment_rad, ranges_m}) sets the depth the zoom assumes
   * (once per scan, at 10 Hz, rather than on every drawn frame). */
  setScan(scan) {
    if (scan && typeof scan === "object") this.#depthM = referenceDepthFromScan(scan, cameraModel(this.#info));
  }

  reset(sequenceBase) {
    this.log.reset(sequenceBase);
  }

  recordSent(message, nowMs) {
    if (message && (message.type === "drive" || message.type === "stop")) this.log.recordSent(message, nowMs);
  }

  recordFrame(header, nowMs) {
    this.log.recordFrame(header, nowMs);
  }

  /** Command-to-video delay when measured, else the frame's age by the clocks [ms]. */
  videoDelayMs(header, nowUnixMs) {
    if (Number.isFinite(this.log.measuredDelayMs)) return this.log.measuredDelayMs;
    const captureS = Number(header?.capture_unix_s);
    return Number.isFinite(captureS) ? Math.max(0, nowUnixMs - captureS * 1000) : NaN;
  }

  /** The transform last drawn (for tests and the benchmark). */
  get lastTransform() {
    return this.#lastTransform;
  }

  /**
   * Draws bitmap on canvas, warped when enabled; returns true while the prediction is still moving.
   */
  draw(canvas, bitmap, nowMs) {
    const ctx = canvas.getContext("2d");
    const camera = cameraModel({ ...this.#info, width: canvas.width, height: canvas.height });
    const pose = this.enabled ? this.log.predict(nowMs) : { x_m: 0, y_m: 0, theta_rad: 0, linear_mps: 0, angular_radps: 0 };
    const depthM = this.#depthM;
    const transform = warpTransform(pose, camera, Number.isFinite(depthM) ? depthM : undefined);
    this.#lastTransform = { ...transform, pose, depthM };
    canvas.dataset.warpShiftPx = transform.shiftX.toFixed(1); // data, not text: a data attribute
    canvas.dataset.warpScale = transform.scale.toFixed(3); // data, not text: a data attribute
    canvas.dataset.outstandingCommands = String(this.log.outstanding().length);
    drawWarped(ctx, bitmap, transform, this.fill);
    if (!this.enabled) return false;
    const outstanding = this.log.outstanding();
    const present = outstanding.length ? outstanding[outstanding.length - 1] : null;
    this.#drawPath(ctx, camera, present);
    const moving = Math.abs(pose.linear_mps) > IDLE_EPSILON || Math.abs(pose.angular_radps) > IDLE_EPSILON;
    return moving || outstanding.length > 0;
  }

  #drawPath(ctx, camera, command) {
    const points = predictedPathPoints(camera, command);
    if (points.length < 2) return;
    ctx.save();
    ctx.lineWidth = Math.max(2, camera.width / 160);
    ctx.strokeStyle = "rgba(80, 230, 120, 0.9)";
    ctx.setLineDash([camera.width / 40, camera.width / 60]);
    ctx.beginPath();
    points.forEach((point, index) => (index ? ctx.lineTo(point.x, point.y) : ctx.moveTo(point.x, point.y)));
    ctx.stroke();
    ctx.restore();
  }
}
