// Pure maths for the drive pad: which directions are held + speed fraction -> velocity command.
// The server clamps and re-checks every command; these limits only shape what we ask for.

/** The four directions a person can hold; any mix is allowed. */
export const DIRECTIONS = Object.freeze(["forward", "backward", "left", "right"]);

/** Arrow key -> direction. */
export const KEY_DIRECTIONS = Object.freeze({
  ArrowUp: "forward",
  ArrowDown: "backward",
  ArrowLeft: "left",
  ArrowRight: "right",
});

function clampFraction(fraction) {
  const value = Number(fraction);
  if (!Number.isFinite(value)) return 0;
  return Math.min(1, Math.max(0, value));
}

function finiteLimit(limit) {
  const value = Number(limit);
  return Number.isFinite(value) && value > 0 ? value : 0;
}

/**
 * Velocity command for the held directions.
 *
 * @param {Iterable<string>} held  directions currently held ("forward", "backward", "left", "right")
 * @param {number} speedFraction  0..1 share of the robot's limits
 * @param {{max_linear_mps: number, max_angular_radps: number} | null} limits
 * @returns {{linear_mps: number, angular_radps: number}}  angular is positive when turning left
 */
export function driveCommand(held, speedFraction, limits) {
  const directions = new Set(held);
  const fraction = clampFraction(speedFraction);
  const linearAxis = (directions.has("forward") ? 1 : 0) - (directions.has("backward") ? 1 : 0);
  const angularAxis = (directions.has("left") ? 1 : 0) - (directions.has("right") ? 1 : 0);
  // Round to micro-units so the JSON we send stays short and stable ("0.25", not "0.25000000000000006").
  const round = (value) => Math.round(value * 1e6) / 1e6 || 0;
  return {
    linear_mps: round(linearAxis * fraction * finiteLimit(limits?.max_linear_mps)),
    angular_radps: round(angularAxis * fraction * finiteLimit(limits?.max_angular_radps)),
  };
}

/** True when the command asks the robot to stand still. */
export function isStill(command) {
  return command.linear_mps === 0 && command.angular_radps === 0;
}

/** Step mode: how far one press moves. */
export const STEP_DISTANCE_M = 0.1;
export const STEP_ANGLE_RAD = (15 * Math.PI) / 180;

/**
 * One step as a timed drive: the velocity for `direction` at the chosen speed, and for how long.
 * Returns null when the speed is zero (no step can be timed).
 */
export function stepCommand(direction, speedFraction, limits) {
  const command = driveCommand([direction], speedFraction, limits);
  const turning = direction === "left" || direction === "right";
  const speed = Math.abs(turning ? command.angular_radps : command.linear_mps);
  if (!(speed > 0)) return null;
  const duration_ms = Math.round(((turning ? STEP_ANGLE_RAD : STEP_DISTANCE_M) / speed) * 1000);
  return { command, duration_ms };
}

/** Apply a radial dead zone to one stick axis value (-1..1), rescaling the rest to 0..1. */
export function applyDeadZone(value, deadZone = 0.15) {
  const number = Number(value);
  if (!Number.isFinite(number) || Math.abs(number) <= deadZone) return 0;
  return (Math.sign(number) * (Math.min(1, Math.abs(number)) - deadZone)) / (1 - deadZone);
}

/**
 * Gamepad left stick -> velocity: up is forward, left turns left (standard mapping: axes[0] x, axes[1] y).
 */
export function stickCommand(axes, speedFraction, limits, deadZone = 0.15) {
  const fraction = clampFraction(speedFraction);
  const forward = -applyDeadZone(axes?.[1], deadZone);
  const turn = -applyDeadZone(axes?.[0], deadZone);
  const round = (value) => Math.round(value * 1e6) / 1e6 || 0;
  return {
    linear_mps: round(forward * fraction * finiteLimit(limits?.max_linear_mps)),
    angular_radps: round(turn * fraction * finiteLimit(limits?.max_angular_radps)),
  };
}
