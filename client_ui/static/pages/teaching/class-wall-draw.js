// The class wall's tiles drawn from poses: the lab's floor plan (drawn once per tile size into a bitmap) and the
// robot, its short trail and the tutor's pointer on top, with canvas transforms. No transport, no page state: the
// wall page and the benchmark (benchmarks/class_wall.py) draw with the same code.
import { boxCorners, fitView, sceneBounds, worldTransform } from "../../lib/map-geometry.js";

const TRAIL_POINTS = 24;
const STATE_COLOURS = { idle: "#2a6fdb", driving: "#1c8a4a", faulted: "#c0392b", test: "#8e44ad" };

/** A row of the wall's "poses" message as an object. */
export function parsePoseRow(row) {
  const [userId, x_m, y_m, theta_rad, linear_mps, angular_radps, charge, activity] = row;
  return { userId, x_m, y_m, theta_rad, linear_mps, angular_radps, charge, activity };
}

/** The state word a tile shows: faulted, test, plan, skill, driving or idle (seat first, then the robot). */
export function tileState(seat, pose) {
  if (!seat || seat.seat_state !== "ready") return seat?.seat_state === "starting" ? "starting" : "faulted";
  if (pose?.activity === "faulted") return "faulted";
  if (seat.testing) return "test";
  if (!pose) return "idle";
  if (pose.activity?.startsWith("plan:")) return "plan";
  if (pose.activity?.startsWith("skill:")) return "skill";
  return pose.activity === "driving" ? "driving" : "idle";
}

/** The floor plan of the scene boxes at width x height device pixels, and the view that maps the world onto it. */
export function floorPlan(boxes, width, height) {
  const view = fitView(sceneBounds(boxes), width, height, 4);
  const canvas = typeof OffscreenCanvas === "function" ? new OffscreenCanvas(width, height)
    : Object.assign(document.createElement("canvas"), { width, height });
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#f6f8fb";
  ctx.fillRect(0, 0, width, height);
  ctx.setTransform(...worldTransform(view));
  ctx.fillStyle = "#9aa7b8";
  for (const box of boxes ?? []) {
    const corners = boxCorners(box);
    ctx.beginPath();
    ctx.moveTo(...corners[0]);
    for (const corner of corners.slice(1)) ctx.lineTo(...corner);
    ctx.closePath();
    ctx.fill();
  }
  // A bitmap draws faster than a canvas, many times a second; where there is no OffscreenCanvas, the canvas.
  return { canvas: typeof canvas.transferToImageBitmap === "function" ? canvas.transferToImageBitmap() : canvas, view };
}

/** Adds pose to a tile's trail (a few points, for the direction of travel). */
export function grow(trail, pose) {
  const last = trail[trail.length - 1];
  if (!last || Math.hypot(last[0] - pose.x_m, last[1] - pose.y_m) > 0.02) trail.push([pose.x_m, pose.y_m]);
  if (trail.length > TRAIL_POINTS) trail.shift();
  return trail;
}

/** Draws one tile: the plan, the trail, the robot (coloured by state) and the tutor's pointer, if any. */
export function drawTile(ctx, plan, { pose, trail = [], state = "idle", pointer = null, radius_m = 0.17 }) {
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.drawImage(plan.canvas, 0, 0);
  ctx.setTransform(...worldTransform(plan.view));
  const pixel = 1 / plan.view.scale;
  if (trail.length > 1) {
    ctx.strokeStyle = "rgba(42, 111, 219, .45)";
    ctx.lineWidth = 2 * pixel;
    ctx.beginPath();
    ctx.moveTo(...trail[0]);
    for (const point of trail.slice(1)) ctx.lineTo(...point);
    ctx.stroke();
  }
  if (pointer) {
    ctx.strokeStyle = "#e67e22";
    ctx.lineWidth = 2 * pixel;
    ctx.beginPath();
    ctx.arc(pointer.x_m, pointer.y_m, 6 * pixel, 0, 2 * Math.PI);
    ctx.moveTo(pointer.x_m - 9 * pixel, pointer.y_m);
    ctx.lineTo(pointer.x_m + 9 * pixel, pointer.y_m);
    ctx.moveTo(pointer.x_m, pointer.y_m - 9 * pixel);
    ctx.lineTo(pointer.x_m, pointer.y_m + 9 * pixel);
    ctx.stroke();
  }
  if (!pose) return;
  const size = Math.max(radius_m, 5 * pixel);
  ctx.translate(pose.x_m, pose.y_m);
  ctx.rotate(pose.theta_rad);
  ctx.fillStyle = STATE_COLOURS[state] ?? STATE_COLOURS.idle;
  ctx.beginPath();
  ctx.moveTo(size * 1.4, 0);
  ctx.lineTo(-size, size);
  ctx.lineTo(-size, -size);
  ctx.closePath();
  ctx.fill();
}
