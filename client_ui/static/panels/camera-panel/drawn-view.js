// The camera panel's second source: the robot's-eye view drawn by this browser from the robot's scene description
// and each telemetry message's `camera_pose`, where the robot truly stands (a camera shows the world as it is, so
// a drawn picture never drifts with odometry; the middleware withholds it in graded runs, and the panel then shows
// the server's video), as frames with the same header a video frame carries (odometry pose at capture, last
// applied command, capture time), so the motion preview, the video-delay figure and any added delay treat both
// sources alike. three.js is loaded only when this source is first chosen.

import { t } from "../../lib/i18n.js";


const MAX_SCALE = 2; // up to twice the camera's own resolution (640 x 480 for the Telebot) where the screen has it

/** Frames drawn from poses; `create` resolves to null (with `problem`) where WebGL is missing. */
export class DrawnView {
  #renderer;
  #canvas;
  #sequence = 0;

  constructor(renderer, canvas) {
    this.#renderer = renderer;
    this.#canvas = canvas;
  }

  /**
   * A view for scene drawn at `scale` times the camera's resolution (1 on a phone, up to MAX_SCALE elsewhere).
   * @returns {Promise<{view: DrawnView|null, problem: string}>}
   */
  static async create(scene, scale) {
    const { RobotEyeRenderer } = await import("../../lib/robot-eye.js");
    const factor = Math.max(1, Math.min(MAX_SCALE, Math.round(scale)));
    const canvas = document.createElement("canvas");
    try {
      const renderer = new RobotEyeRenderer(canvas, scene, {
        width_px: scene.camera.width_px * factor, height_px: scene.camera.height_px * factor, antialias: factor === 1,
      });
      return { view: new DrawnView(renderer, canvas), problem: "" };
    } catch {
      return { view: null, problem: t("This browser cannot draw the view (WebGL is turned off or missing): the robot's camera video is shown instead.") };
    }
  }

  /** The frame for one telemetry message, {bitmap, header}, or null when it carries no camera pose. */
  async frameFrom(telemetry) {
    const standing = telemetry?.camera_pose;
    if (![standing?.x_m, standing?.y_m, standing?.theta_rad].every(Number.isFinite)) return null;
    const pose = telemetry.odometry?.pose ?? null;
    this.#renderer.render(standing);
    // Taken in the same task as the draw: the canvas still holds it.
    const bitmap = await createImageBitmap(this.#canvas);
    this.#sequence += 1;
    const { width, height } = this.#renderer.size;
    return {
      bitmap,
      header: {
        frame_sequence: this.#sequence, capture_unix_s: telemetry.capture_unix_s, sim_time_s: telemetry.sim_time_s,
        last_applied_sequence: telemetry.last_applied_sequence, pose_at_capture: pose, width_px: width,
        height_px: height, drawn_here: true,
      },
    };
  }

  dispose() {
    this.#renderer.dispose();
  }
}
