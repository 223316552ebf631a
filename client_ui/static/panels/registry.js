// The panel registry (rosboard's Viewer.registerViewer): each panel module registers its kind, tag, default
// width and feeds when it is imported, and the console builds its table of kinds from what registered. A
// new panel kind is a folder here holding <name>/<name>.js (which calls registerPanel) and its CSS, plus
// its folder name in PANEL_MODULES: without a build step the browser cannot list a folder, so that one
// line is the only thing outside the panel's folder that a new kind touches.
//
// Feeds say what the console's wiring connects to the panel; panels themselves never open a socket:
//   {socket: "telemetry", messages: {telemetry: "telemetry", status: "message"}}
//       a text socket of the robot (the descriptor's channel when it ends with /<socket>, otherwise
//       /ws/robots/<r>/<socket>): each parsed message whose `type` is listed is set on that property;
//   {robotInfo: "info"} (optionally `fields: [...]`, to pass only those)
//       the robot's description (GET /api/robots/<r>) set on that property once it is loaded;
//   {service: "<name>"}
//       one of the console's exchanges that is more than a socket read (the drive session, skill goals,
//       the turn queue, chat, the camera's binary stream, the map's polling and targets, response times), which
//       its module registers in lib/console/feed-services.js (as a panel registers here).

import { elementRegistrar } from "./panel-base.js";

/** The folders of the panel modules the console loads; each registers one kind. */
export const PANEL_MODULES = Object.freeze([
  "camera-panel", "map-panel", "lab-view", "room-camera", "odometry-panel", "sonar-panel", "laser-panel", "drive-pad",
  "skill-panel", "queue-panel", "chat-panel", "response-times-panel", "low-level-panel", "plan-panel", "line-sensor",
]);

const panels = new Map();

/**
 * Register a panel kind; returns the module's `register()` (define the element and add its stylesheets).
 *
 * @param {{kind: string, tag: string, element: CustomElementConstructor, stylesheets?: URL[], span?: 1|2,
 *          feeds?: object[], check?: (descriptor: object) => string}} spec
 *        `check` returns a problem with a descriptor of this kind (in words), or "" when it is usable.
 */
export function registerPanel({ kind, tag, element, stylesheets = [], span = 1, feeds = [], check = null }) {
  if (panels.has(kind)) throw new Error(`two panel modules register the kind "${kind}"`);
  const register = elementRegistrar(tag, element, stylesheets);
  panels.set(kind, Object.freeze({ kind, tag, span, feeds: Object.freeze([...feeds]), check, register }));
  return register;
}

/** The registered panel kinds: kind -> {kind, tag, span, feeds, check, register}. */
export function registeredPanels() {
  return new Map(panels);
}

/**
 * Import every panel module (each registers itself); a module that fails costs its own kind only.
 *
 * @returns {Promise<{panels: Map, failed: {module: string, problem: string}[]}>}
 */
export async function loadPanels() {
  const results = await Promise.all(PANEL_MODULES.map((name) => import(new URL(`./${name}/${name}.js`, import.meta.url).href)
    .then(() => null, (error) => ({ module: name, problem: error?.message ?? String(error) }))));
  return { panels: registeredPanels(), failed: results.filter(Boolean) };
}
