// The camera's feedback layer: draws the last frame moved by the commands it does not show yet, and the
// predicted path on the floor. All maths is in feedback-math.js; here it becomes two setTransform calls and
// one drawImage (GPU-friendly; no per-pixel loop).

import { CommandLog, cameraModel, predictedPathPoints, warpTransform } from "../../js/feedback-math.js";

const IDLE_EPSILON = 1e-4;

export class FeedbackLayer {
  enabled = true;
  log = new CommandLog();
  #info = {};
  #lastTransform = null;

  setInfo(info) {
    if (!info || typeof info !== "object") return;
    this.#info = {
      hfovDeg: Number(info.camera_hfov_deg) || undefined,
      width: Number(info.camera_width_px) || undefined,
      height: Number(info.camera_height_px) || undefined,
    };
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
    const transform = warpTransform(pose, camera);
    this.#lastTransform = { ...transform, pose };
    canvas.dataset.warpShiftPx = transform.shiftX.toFixed(1);
    canvas.dataset.warpScale = transform.scale.toFixed(3);
    canvas.dataset.outstandingCommands = String(this.log.outstanding().length);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    const warped = Math.abs(transform.shiftX) > 0.05 || Math.abs(transform.scale - 1) > 1e-3;
    if (warped) {
      ctx.fillStyle = "#000";
      ctx.fillRect(0, 0, canvas.width, canvas.height);
      ctx.setTransform(transform.scale, 0, 0, transform.scale, transform.tx, transform.ty);
    }
    ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
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
