// Pure checks of the panel descriptors the middleware sends (GET /api/robots/<r>/panels).
// A descriptor that fails here is shown as a notice in its place; it never stops the page.

/** The panel kinds this client knows how to place. */
export const KNOWN_KINDS = Object.freeze([
  "camera", "map", "odometry", "sonar", "laser", "drive", "skill", "queue", "chat", "response-times",
]);
const PARAMETER_TYPES = new Set(["double", "int", "bool", "enum", "string"]);
const ID_PATTERN = /^[A-Za-z0-9_.:-]{1,64}$/;

function isPlainObject(value) {
  return value !== null && typeof value === "object" && !Array.isArray(value);
}

function checkParameter(parameter, index) {
  if (!isPlainObject(parameter)) return `parameter ${index + 1} is not an object`;
  if (typeof parameter.name !== "string" || !parameter.name) return `parameter ${index + 1} has no name`;
  if (!PARAMETER_TYPES.has(parameter.type)) return `parameter ${parameter.name} has an unknown type`;
  if (parameter.type === "enum" && !Array.isArray(parameter.choices)) return `parameter ${parameter.name} has no choices`;
  return "";
}

/**
 * Check one descriptor.
 *
 * @returns {{ok: true, descriptor: object} | {ok: false, problem: string, title: string}}
 */
export function checkDescriptor(descriptor, seenIds = new Set()) {
  const fail = (problem) => ({
    ok: false, problem, title: isPlainObject(descriptor) && typeof descriptor.title === "string" ? descriptor.title : "",
  });
  if (!isPlainObject(descriptor)) return fail("the description is not an object");
  if (typeof descriptor.id !== "string" || !ID_PATTERN.test(descriptor.id)) return fail("the panel has no usable id");
  if (seenIds.has(descriptor.id)) return fail(`two panels share the id ${descriptor.id}`);
  if (typeof descriptor.kind !== "string") return fail("the panel has no kind");
  if (!KNOWN_KINDS.includes(descriptor.kind)) return fail(`this console does not know panels of kind "${descriptor.kind}"`);
  if (typeof descriptor.title !== "string" || !descriptor.title.trim()) return fail("the panel has no title");
  const channel = descriptor.channel ?? null;
  if (channel !== null && (typeof channel !== "string" || !channel.startsWith("/ws/"))) {
    return fail("the panel's data channel is not a WebSocket path");
  }
  if (descriptor.kind === "skill") {
    if (typeof descriptor.skill !== "string" || !descriptor.skill) return fail("the skill panel names no skill");
    if (!Array.isArray(descriptor.schema)) return fail("the skill panel has no parameter schema");
    for (const [index, parameter] of descriptor.schema.entries()) {
      const problem = checkParameter(parameter, index);
      if (problem) return fail(problem);
    }
  }
  return {
    ok: true,
    descriptor: { ...descriptor, channel, help: typeof descriptor.help === "string" ? descriptor.help : "" },
  };
}

/** Check a whole panels answer; returns entries in the order sent, each ok or a problem. */
export function checkPanelList(answer) {
  if (!isPlainObject(answer) || !Array.isArray(answer.panels)) return null;
  const seen = new Set();
  return answer.panels.map((descriptor) => {
    const result = checkDescriptor(descriptor, seen);
    if (result.ok) seen.add(result.descriptor.id);
    return result;
  });
}

/** The skill whose schema has goal x/y parameters (names ending in x_m and y_m), preferring "goal_" names. */
export function goalParameterNames(schema) {
  if (!Array.isArray(schema)) return null;
  const names = schema.filter((p) => p?.type === "double" || p?.type === "int").map((p) => p.name);
  for (const prefix of ["goal_", "target_", ""]) {
    const x = names.find((name) => name === `${prefix}x_m` || (prefix === "" && /(^|_)x_m$/.test(name)));
    const y = names.find((name) => name === `${prefix}y_m` || (prefix === "" && /(^|_)y_m$/.test(name)));
    if (x && y) return { x, y };
  }
  return null;
}
