// Pure geometry of the lab map: the world (metres, y up) <-> canvas (pixels, y down) transform,
// and the shapes the map draws (boxes, sensor cones, laser points). No DOM, so it tests in isolation.

/** Bounds {minX, maxX, minY, maxY} of scene boxes, grown by margin_m; a 6 m square when there are none. */
export function sceneBounds(boxes, margin_m = 0.3) {
  const points = (boxes ?? []).flatMap(boxCorners);
  if (!points.length) return { minX: -3, maxX: 3, minY: -3, maxY: 3 };
  const xs = points.map(([x]) => x);
  const ys = points.map(([, y]) => y);
  return { minX: Math.min(...xs) - margin_m, maxX: Math.max(...xs) + margin_m,
    minY: Math.min(...ys) - margin_m, maxY: Math.max(...ys) + margin_m };
}

/**
 * The view that fits `bounds` into a width x height canvas, keeping the aspect ratio.
 * canvas = (offsetX + x * scale, offsetY - y * scale).
 */
export function fitView(bounds, width, height, padding_px = 8) {
  const spanX = Math.max(1e-6, bounds.maxX - bounds.minX);
  const spanY = Math.max(1e-6, bounds.maxY - bounds.minY);
  const scale = Math.max(1e-6, Math.min((width - 2 * padding_px) / spanX, (height - 2 * padding_px) / spanY));
  const offsetX = width / 2 - ((bounds.minX + bounds.maxX) / 2) * scale;
  const offsetY = height / 2 + ((bounds.minY + bounds.maxY) / 2) * scale;
  return { scale, offsetX, offsetY };
}

/** World point -> canvas pixels. */
export function worldToCanvas(view, x_m, y_m) {
  return [view.offsetX + x_m * view.scale, view.offsetY - y_m * view.scale];
}

/** Canvas pixels -> world point. */
export function canvasToWorld(view, px, py) {
  return [(px - view.offsetX) / view.scale, (view.offsetY - py) / view.scale];
}

/** The canvas transform (for ctx.setTransform) that draws in world metres. */
export function worldTransform(view) {
  return [view.scale, 0, 0, -view.scale, view.offsetX, view.offsetY];
}

/** The four corners of a (possibly rotated) scene box, counter-clockwise. */
export function boxCorners(box) {
  const c = Math.cos(Number(box.yaw_rad) || 0);
  const s = Math.sin(Number(box.yaw_rad) || 0);
  const hx = Number(box.half_x_m);
  const hy = Number(box.half_y_m);
  return [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]].map(([dx, dy]) =>
    [Number(box.center_x_m) + dx * c - dy * s, Number(box.center_y_m) + dx * s + dy * c]);
}

/** Robot-frame point at `range_m` along `bearing_rad` -> world point, for a robot at `pose`. */
export function robotToWorld(pose, range_m, bearing_rad) {
  const angle = pose.theta_rad + bearing_rad;
  return [pose.x_m + range_m * Math.cos(angle), pose.y_m + range_m * Math.sin(angle)];
}

/** World points of the laser's valid hits (finite and inside its range). */
export function laserHits(pose, scan, maxRange_m = Infinity) {
  const ranges = scan?.ranges_m ?? [];
  const start = Number(scan?.angle_min_rad);
  const step = Number(scan?.angle_increment_rad);
  if (!pose || !Number.isFinite(start) || !Number.isFinite(step)) return [];
  const hits = [];
  ranges.forEach((range, index) => {
    if (Number.isFinite(range) && range > 0 && range < maxRange_m - 1e-3) {
      hits.push(robotToWorld(pose, range, start + index * step));
    }
  });
  return hits;
}

/** A sonar's cone as a polygon in world coordinates (apex at the robot centre). */
export function sonarCone(pose, sonar, range_m, segments = 6) {
  const half = Number(sonar.cone_half_angle_rad) || 0.13;
  const points = [[pose.x_m, pose.y_m]];
  for (let i = 0; i <= segments; i += 1) {
    points.push(robotToWorld(pose, range_m, Number(sonar.mount_angle_rad) - half + (2 * half * i) / segments));
  }
  return points;
}

/** Move a keyboard cursor by (dx, dy) metres, kept inside bounds. */
export function moveCursor(cursor, dx_m, dy_m, bounds) {
  const clamp = (value, low, high) => Math.min(high, Math.max(low, value));
  return [clamp(cursor[0] + dx_m, bounds.minX, bounds.maxX), clamp(cursor[1] + dy_m, bounds.minY, bounds.maxY)];
}

/**
 * The trail with `pose` added: a point only once the robot moved `minStep_m`, the oldest dropped past
 * `maxPoints`, and a fresh trail when the pose jumped `jump_m` (a reset or a re-localization, not a move).
 */
export function extendTrail(trail, pose, { minStep_m = 0.03, jump_m = 1.0, maxPoints = 1500 } = {}) {
  if (!pose) return trail;
  const point = [pose.x_m, pose.y_m];
  const last = trail[trail.length - 1];
  if (!last) return [point];
  const step = Math.hypot(point[0] - last[0], point[1] - last[1]);
  if (step > jump_m) return [point];
  if (step < minStep_m) return trail;
  const grown = [...trail, point];
  return grown.length > maxPoints ? grown.slice(grown.length - maxPoints) : grown;
}

/** Distance in metres between two poses' positions. */
export function poseDistance(a, b) {
  return Math.hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}
