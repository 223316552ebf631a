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
