// Pure maths of the camera feedback layer (thesis algorithms 3.1 and 3.2, equation 1, done with a
// camera model): (frame metadata, commands sent since) -> predicted motion -> one canvas transform.
// No DOM here, so it is testable anywhere; the camera panel draws the result with setTransform.

const DEG = Math.PI / 180;

/** The Telebot's camera (skill_server RobotSpec/CameraSpec): 60 deg, 0.30 m high, pitched 12 deg down. */
export const DEFAULT_CAMERA = Object.freeze({
  width: 320, height: 240, hfovDeg: 60, heightM: 0.30, pitchDownDeg: 12,
});

/** The robot's limits the prediction follows (acceleration ramps and the deadman's hold). */
export const DEFAULT_MOTION = Object.freeze({
  maxLinearAccelMps2: 1.0, maxAngularAccelRadps2: 3.0, holdMs: 400, stepMs: 10,
});

/** Distance of the surface the forward/back scaling assumes [m] when nothing better is known. */
export const DEFAULT_REFERENCE_DEPTH_M = 1.5;

/** Bounds of a measured reference depth [m]: nearer than the bumper or beyond the lab means a bad reading. */
export const REFERENCE_DEPTH_LIMITS_M = Object.freeze({ min: 0.3, max: 8 });

/** Fewest laser beams inside the field of view that make a depth worth trusting. */
const MIN_DEPTH_BEAMS = 5;

/**
 * Pinhole model of the camera at a given image size.
 * @returns {{width, height, f, cx, cy, vpX, vpY, heightM, pitchDown}} f, cx, cy, vp in pixels
 */
export function cameraModel(options = {}) {
  const spec = { ...DEFAULT_CAMERA, ...options };
  const width = Number(spec.width) > 0 ? Number(spec.width) : DEFAULT_CAMERA.width;
  const height = Number(spec.height) > 0 ? Number(spec.height) : DEFAULT_CAMERA.height;
  const hfov = (Number(spec.hfovDeg) > 1 && Number(spec.hfovDeg) < 179 ? Number(spec.hfovDeg) : 60) * DEG;
  const f = (width / 2) / Math.tan(hfov / 2);
  const pitchDown = Number(spec.pitchDownDeg) * DEG;
  const cx = width / 2;
  const cy = height / 2;
  // Forward motion on a level floor expands the image about the horizon straight ahead.
  return { width, height, f, cx, cy, vpX: cx, vpY: cy - f * Math.tan(pitchDown), heightM: Number(spec.heightM), pitchDown };
}

/** This socket's number for a robot-side sequence (frames carry the robot's; the drive socket adds its base). */
export function clientSequence(robotSequence, sequenceBase) {
  const applied = Number(robotSequence) - Number(sequenceBase);
  return Number.isFinite(applied) ? Math.max(0, applied) : 0;
}

/** The commands a frame does not show yet: those numbered after the frame's last applied command. */
export function outstandingCommands(commands, appliedClientSequence) {
  return commands.filter((command) => command.sequence > appliedClientSequence);
}

/** The last command the frame does show (its velocity is what the robot had when the frame was taken). */
export function lastAppliedCommand(commands, appliedClientSequence) {
  let found = null;
  for (const command of commands) if (command.sequence <= appliedClientSequence) found = command;
  return found;
}

function approach(value, target, maxStep) {
  if (target > value) return Math.min(target, value + maxStep);
  return Math.max(target, value - maxStep);
}

/**
 * Motion of the robot from the frame's capture to nowMs, in the robot's frame at capture (x ahead, y left).
 *
 * Each command holds from its sending until the next one (at most the deadman's hold, after which the
 * robot stops); velocities ramp at the robot's acceleration limits, starting from `initial` (the
 * velocity of the last command the frame shows). Equation 1 of the thesis is the special case of
 * 20 Hz turn inputs with no ramp: angle = sum of omega/20.
 *
 * @param {Array<{sequence, sentMs, linear_mps, angular_radps}>} commands outstanding, in sending order
 * @returns {{x_m, y_m, theta_rad, linear_mps, angular_radps}} pose change and the velocity reached
 */
export function integrateCommands(commands, nowMs, initial = null, motion = {}) {
  const m = { ...DEFAULT_MOTION, ...motion };
  let v = Number(initial?.linear_mps) || 0;
  let w = Number(initial?.angular_radps) || 0;
  let x = 0;
  let y = 0;
  let theta = 0;
  if (!commands.length) return { x_m: 0, y_m: 0, theta_rad: 0, linear_mps: v, angular_radps: w };
  let t = commands[0].sentMs;
  for (let i = 0; i < commands.length; i += 1) {
    const command = commands[i];
    const nextMs = i + 1 < commands.length ? Math.min(commands[i + 1].sentMs, nowMs) : nowMs;
    const holdEnd = command.sentMs + m.holdMs;
    while (t < nextMs - 1e-9) {
      const stepEnd = Math.min(nextMs, t + m.stepMs);
      const step = (stepEnd - t) / 1000;
      const held = t < holdEnd;
      const targetV = held ? Number(command.linear_mps) || 0 : 0;
      const targetW = held ? Number(command.angular_radps) || 0 : 0;
      v = approach(v, targetV, m.maxLinearAccelMps2 * step);
      w = approach(w, targetW, m.maxAngularAccelRadps2 * step);
      // Midpoint heading keeps arcs accurate at this step size.
      const mid = theta + (w * step) / 2;
      x += v * Math.cos(mid) * step;
      y += v * Math.sin(mid) * step;
      theta += w * step;
      t = stepEnd;
      if (!held && v === 0 && w === 0) { t = nextMs; break; }
    }
  }
  return { x_m: x, y_m: y, theta_rad: theta, linear_mps: v, angular_radps: w };
}

/**
 * The affine canvas transform that turns the stale frame into the predicted view.
 *
 * A reference point straight ahead at depth `referenceDepthM` is followed into the camera's new pose: its
 * bearing gives the sideways shift (f * tan, so a turn of theta shifts by ~theta/hfov of the width, algorithm
 * 3.1), its new distance the scale about the vanishing point (algorithm 3.2's intent: nearer looks bigger).
 *
 * @returns {{scale, tx, ty, shiftX, visible}} for ctx.setTransform(scale, 0, 0, scale, tx, ty);
 *   visible is false when the predicted view shares nothing with the frame (all black).
 */
export function warpTransform(pose, camera, referenceDepthM = DEFAULT_REFERENCE_DEPTH_M) {
  const depth = Math.max(0.2, Number(referenceDepthM) || DEFAULT_REFERENCE_DEPTH_M);
  const theta = Number(pose.theta_rad) || 0;
  const dx = depth - (Number(pose.x_m) || 0);
  const dy = -(Number(pose.y_m) || 0);
  // The reference point in the robot's new frame (rotate by -theta).
  const ahead = Math.cos(theta) * dx + Math.sin(theta) * dy;
  const left = -Math.sin(theta) * dx + Math.cos(theta) * dy;
  const bearing = Math.atan2(left, ahead);
  const halfFov = Math.atan(camera.cx / camera.f);
  let shiftX;
  if (Math.abs(bearing) >= Math.PI / 2 - 1e-3 || ahead <= 0) shiftX = Math.sign(-bearing || 1) * camera.width * 4;
  else shiftX = -camera.f * Math.tan(bearing);
  const distance = Math.hypot(ahead, left);
  const scale = Math.min(4, Math.max(0.25, depth / Math.max(distance, depth * 0.25)));
  const visible = Math.abs(bearing) < halfFov * 2 && ahead > 0;
  return {
    scale,
    tx: camera.vpX * (1 - scale) + shiftX,
    ty: camera.vpY * (1 - scale),
    shiftX,
    visible,
  };
}

/**
 * How far away the surfaces that fill the picture are, from a laser scan: the median range of the beams inside
 * the camera's field of view. The forward/back scaling is right for that depth (a fixed guess is not: the
 * lab's walls are 0.5 to 5 m away). NaN when the scan has too few readings there.
 * @param {{angle_min_rad, angle_increment_rad, ranges_m}} scan the telemetry's laser scan (x ahead, angles left)
 */
export function referenceDepthFromScan(scan, camera) {
  const ranges = Array.isArray(scan?.ranges_m) ? scan.ranges_m : [];
  const angleMin = Number(scan?.angle_min_rad);
  const increment = Number(scan?.angle_increment_rad);
  if (!Number.isFinite(angleMin) || !Number.isFinite(increment) || increment <= 0) return NaN;
  const halfFov = Math.atan(camera.cx / camera.f);
  const inView = [];
  ranges.forEach((range, index) => {
    const value = Number(range);
    if (Math.abs(angleMin + index * increment) <= halfFov && Number.isFinite(value) && value > 0) inView.push(value);
  });
  if (inView.length < MIN_DEPTH_BEAMS) return NaN;
  inView.sort((a, b) => a - b);
  const middle = Math.floor(inView.length / 2);
  const median = inView.length % 2 ? inView[middle] : (inView[middle - 1] + inView[middle]) / 2;
  return Math.min(REFERENCE_DEPTH_LIMITS_M.max, Math.max(REFERENCE_DEPTH_LIMITS_M.min, median));
}

/** True when a transform moves the picture at all (otherwise the frame is drawn as it came). */
export function isWarped(transform) {
  return Math.abs(transform.shiftX) > 0.05 || Math.abs(transform.scale - 1) > 1e-3;
}

/**
 * Where the warped picture leaves the canvas uncovered, and which of its edge pixels continue into each part:
 * the canvas is cut into 3 x 3 zones around the picture; every zone but the centre is filled by stretching the
 * picture's nearest edge row, column or corner pixel (what a clamp-to-edge texture would show). Each entry is
 * drawImage's 8 numbers [sx, sy, sw, sh, dx, dy, dw, dh], source in the bitmap's pixels, destination in the
 * canvas's (identity transform); the picture itself covers the canvas scaled by `scale` and moved by tx, ty.
 */
export function edgeFillRects(transform, source, target) {
  const { scale, tx, ty } = transform;
  const sw = Number(source.width);
  const sh = Number(source.height);
  const cw = Number(target.width);
  const ch = Number(target.height);
  const clampX = (value) => Math.min(cw, Math.max(0, value));
  const clampY = (value) => Math.min(ch, Math.max(0, value));
  const left = clampX(tx);
  const right = clampX(tx + scale * cw);
  const top = clampY(ty);
  const bottom = clampY(ty + scale * ch);
  // Source span of the picture's visible middle band, in bitmap pixels.
  const toSourceX = (x) => ((x - tx) / scale) * (sw / cw);
  const toSourceY = (y) => ((y - ty) / scale) * (sh / ch);
  const columns = [
    { d0: 0, d1: left, s0: 0, s1: 1 },
    { d0: left, d1: right, s0: toSourceX(left), s1: toSourceX(right) },
    { d0: right, d1: cw, s0: sw - 1, s1: sw },
  ];
  const rows = [
    { d0: 0, d1: top, s0: 0, s1: 1 },
    { d0: top, d1: bottom, s0: toSourceY(top), s1: toSourceY(bottom) },
    { d0: bottom, d1: ch, s0: sh - 1, s1: sh },
  ];
  const rects = [];
  rows.forEach((row, r) => columns.forEach((column, c) => {
    if ((r === 1 && c === 1) || column.d1 - column.d0 < 0.5 || row.d1 - row.d0 < 0.5) return;
    rects.push([column.s0, row.s0, Math.max(1e-3, column.s1 - column.s0), Math.max(1e-3, row.s1 - row.s0),
      column.d0, row.d0, column.d1 - column.d0, row.d1 - row.d0]);
  }));
  return rects;
}

/** Image point of a floor point (x ahead, y left of the camera, metres), or null behind/above the horizon. */
export function projectFloorPoint(camera, xAheadM, yLeftM) {
  const cosP = Math.cos(camera.pitchDown);
  const sinP = Math.sin(camera.pitchDown);
  const depth = xAheadM * cosP + camera.heightM * sinP;
  if (depth <= 0.05) return null;
  const up = xAheadM * sinP - camera.heightM * cosP;
  return { x: camera.cx - (camera.f * yLeftM) / depth, y: camera.cy - (camera.f * up) / depth };
}

/**
 * The floor path the robot will follow if the present command holds for horizonS, as image points
 * (from the predicted present pose, i.e. in the warped view). Empty when standing still.
 */
export function predictedPathPoints(camera, command, { horizonS = 2, steps = 24, cameraForwardM = 0.17 } = {}) {
  const v = Number(command?.linear_mps) || 0;
  const w = Number(command?.angular_radps) || 0;
  if (Math.abs(v) < 1e-3) return [];
  const points = [];
  let x = 0;
  let y = 0;
  let theta = 0;
  const dt = horizonS / steps;
  for (let i = 0; i <= steps; i += 1) {
    const point = projectFloorPoint(camera, x - cameraForwardM, y);
    if (point) points.push(point);
    const mid = theta + (w * dt) / 2;
    x += v * Math.cos(mid) * dt;
    y += v * Math.sin(mid) * dt;
    theta += w * dt;
  }
  return points;
}

/**
 * Bookkeeping of the commands sent on one drive socket and the frames that show them.
 * Pure state machine: every method takes the time it happens at.
 */
export class CommandLog {
  constructor({ maxCommands = 400 } = {}) {
    this.commands = [];
    this.sequenceBase = 0;
    this.appliedClientSequence = 0;
    this.measuredDelayMs = NaN;
    this.maxCommands = maxCommands;
  }

  /** A new drive socket (its "ready"): numbering starts again above sequenceBase. */
  reset(sequenceBase) {
    this.commands = [];
    this.sequenceBase = Number(sequenceBase) || 0;
    this.appliedClientSequence = 0;
  }

  /** One message sent on the drive socket ({type: drive|stop, sequence, linear_mps, angular_radps}). */
  recordSent(message, nowMs) {
    const stop = message.type === "stop";
    this.commands.push({
      sequence: Number(message.sequence),
      sentMs: nowMs,
      linear_mps: stop ? 0 : Number(message.linear_mps) || 0,
      angular_radps: stop ? 0 : Number(message.angular_radps) || 0,
    });
    if (this.commands.length > this.maxCommands) this.commands.splice(0, this.commands.length - this.maxCommands);
  }

  /**
   * A frame arrived: remember what it shows, measure the command-to-video delay from the newest command it
   * shows, and forget the commands before that one (it is kept: its velocity is the robot's at capture).
   */
  recordFrame(header, nowMs) {
    const applied = clientSequence(header.last_applied_sequence, this.sequenceBase);
    if (applied > this.appliedClientSequence) {
      const shown = lastAppliedCommand(this.commands, applied);
      if (shown && shown.sequence > this.appliedClientSequence) this.measuredDelayMs = nowMs - shown.sentMs;
    }
    this.appliedClientSequence = Math.max(this.appliedClientSequence, applied);
    const keepFrom = this.commands.findIndex((c) => c.sequence > this.appliedClientSequence);
    const cut = keepFrom === -1 ? this.commands.length - 1 : keepFrom - 1;
    if (cut > 0) this.commands.splice(0, cut);
    return applied;
  }

  /** Commands the last frame does not show. */
  outstanding() {
    return outstandingCommands(this.commands, this.appliedClientSequence);
  }

  /** Predicted pose change since the displayed frame, at nowMs. */
  predict(nowMs, motion = {}) {
    const initial = lastAppliedCommand(this.commands, this.appliedClientSequence);
    return integrateCommands(this.outstanding(), nowMs, initial, motion);
  }
}
