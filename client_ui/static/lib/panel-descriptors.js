// Pure checks of the panel descriptors the middleware sends (GET /api/robots/<r>/panels), against the panel
// kinds that registered (static/panels/registry.js): the kind's own `check` looks at its extra fields (a
// skill's schema). A descriptor that fails here is shown as a notice in its place; it never stops the page.

import { t } from "./i18n.js";


const ID_PATTERN = /^[A-Za-z0-9_.:-]{1,64}$/;

function isPlainObject(value) {
  return value !== null && typeof value === "object" && !Array.isArray(value);
}

/**
 * Check one descriptor; `panels` maps each known kind to {check?(descriptor) -> problem or ""}.
 *
 * @returns {{ok: true, descriptor: object} | {ok: false, problem: string, title: string}}
 */
export function checkDescriptor(descriptor, { panels = new Map(), seenIds = new Set() } = {}) {
  const fail = (problem) => ({
    ok: false, problem, title: isPlainObject(descriptor) && typeof descriptor.title === "string" ? descriptor.title : "",
  });
  if (!isPlainObject(descriptor)) return fail(t("the description is not an object"));
  if (typeof descriptor.id !== "string" || !ID_PATTERN.test(descriptor.id)) return fail(t("the panel has no usable id"));
  if (seenIds.has(descriptor.id)) return fail(t("two panels share the id {id}", { id: descriptor.id }));
  if (typeof descriptor.kind !== "string") return fail(t("the panel has no kind"));
  const panel = panels.get(descriptor.kind);
  if (!panel) return fail(t("this console does not know panels of kind \"{kind}\"", { kind: descriptor.kind }));
  if (typeof descriptor.title !== "string" || !descriptor.title.trim()) return fail(t("the panel has no title"));
  const channel = descriptor.channel ?? null;
  if (channel !== null && (typeof channel !== "string" || !channel.startsWith("/ws/"))) {
    return fail(t("the panel's data channel is not a WebSocket path"));
  }
  const problem = panel.check ? panel.check(descriptor) : "";
  if (problem) return fail(problem);
  return {
    ok: true,
    descriptor: { ...descriptor, channel, help: typeof descriptor.help === "string" ? descriptor.help : "" },
  };
}

/** Check a whole panels answer against the known kinds; returns entries in the order sent, each ok or a problem. */
export function checkPanelList(answer, panels) {
  if (!isPlainObject(answer) || !Array.isArray(answer.panels)) return null;
  const seen = new Set();
  return answer.panels.map((descriptor) => {
    const result = checkDescriptor(descriptor, { panels, seenIds: seen });
    if (result.ok) seen.add(result.descriptor.id);
    return result;
  });
}

/** The parameters of a pose guess, kept filled from the robot's current pose (localization's initial guess). */
export const GUESS_FIELDS = Object.freeze({ x: "initial_x_m", y: "initial_y_m", theta: "initial_theta_rad" });

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
