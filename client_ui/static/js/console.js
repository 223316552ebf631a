// The lab console page (the paper's ExperimentTool): asks the middleware which panels this robot's
// abstractions describe, places them in the order sent, and wires each to its data by kind. It knows no
// panel's insides: a kind maps to a custom element and a wiring; an unknown kind becomes a notice.

import { ApiError, fetchJson } from "./transport.js";
import { h } from "./dom.js";
import { checkPanelList } from "./panel-descriptors.js";
import { ConsoleLayout } from "./console-layout.js";
import { ConsoleWiring } from "./console-wiring.js";
import * as connectionStatus from "../panels/connection-status/connection-status.js";

const panelModule = (name) => new URL(`../panels/${name}/${name}.js`, import.meta.url).href;

/**
 * kind -> the custom element that shows it, the module defining it (loaded on demand, so one broken
 * panel module costs that panel only) and its default width in grid columns.
 */
export const PANEL_REGISTRY = Object.freeze({
  camera: { module: panelModule("camera-panel"), tag: "camera-panel", span: 2 },
  map: { module: panelModule("map-panel"), tag: "map-panel", span: 2 },
  odometry: { module: panelModule("odometry-panel"), tag: "odometry-panel", span: 1 },
  sonar: { module: panelModule("sonar-panel"), tag: "sonar-panel", span: 1 },
  laser: { module: panelModule("laser-panel"), tag: "laser-panel", span: 1 },
  drive: { module: panelModule("drive-pad"), tag: "drive-pad", span: 1 },
  skill: { module: panelModule("skill-panel"), tag: "skill-panel", span: 1 },
  queue: { module: panelModule("queue-panel"), tag: "queue-panel", span: 1 },
  chat: { module: panelModule("chat-panel"), tag: "chat-panel", span: 1 },
  "response-times": { module: panelModule("response-times-panel"), tag: "response-times-panel", span: 1 },
});

const LAYOUT_PREFERENCE = "/api/me/preferences/console-layout";

/** The panels every robot had before the middleware described them; used only if the list cannot be had. */
function basicPanels(robotPath) {
  return [
    { id: "camera", kind: "camera", title: "Camera", channel: `${robotPath}/camera` },
    { id: "queue", kind: "queue", title: "Turn", channel: `${robotPath}/queue` },
    { id: "drive", kind: "drive", title: "Drive", channel: `${robotPath}/drive` },
    { id: "odometry", kind: "odometry", title: "Odometry", channel: `${robotPath}/telemetry` },
    { id: "chat", kind: "chat", title: "Chat", channel: `${robotPath}/chat` },
  ];
}

function showPageError(root, text) {
  const line = root.querySelector("#console-error");
  line.textContent = text;
  line.hidden = !text;
}

async function loadPanelList(robotName, robotPath) {
  try {
    const answer = await fetchJson(`/api/robots/${encodeURIComponent(robotName)}/panels`);
    const checked = checkPanelList(answer);
    if (checked) return { entries: checked, problem: "" };
    return { entries: checkPanelList({ panels: basicPanels(robotPath) }),
      problem: "The robot's panel list could not be read; showing the basic panels." };
  } catch (error) {
    const why = error instanceof ApiError ? error.message : "it could not be loaded";
    return { entries: checkPanelList({ panels: basicPanels(robotPath) }),
      problem: `The robot's panel list is unavailable (${why}); showing the basic panels.` };
  }
}

async function loadSavedLayout() {
  try {
    const answer = await fetchJson(LAYOUT_PREFERENCE);
    return answer?.value && typeof answer.value === "object" ? answer.value : null;
  } catch {
    return null; // no saved layout (or no preferences service): the server's order it is
  }
}

async function start() {
  const root = document.querySelector("#console[data-robot]");
  if (!root) return;
  const robotName = root.dataset.robot;
  const robotPath = `/ws/robots/${encodeURIComponent(robotName)}`;

  connectionStatus.register();
  const status = h("connection-status");
  root.querySelector('[data-slot="status"]').append(status);
  status.robotName = robotName;
  status.loginUrl = root.dataset.loginUrl || "/login";

  const grid = root.querySelector('[data-slot="panels"]');
  const layout = new ConsoleLayout(grid, root.querySelector('[data-slot="panels-menu"]'), {
    save: (value) => fetchJson(LAYOUT_PREFERENCE, { method: "PUT", body: { value } }),
    onSaveError: (error) => showPageError(root, `Your panel layout was not saved: ${error.message}`),
  });
  const wiring = new ConsoleWiring({ root, robotName, robotPath, status, layout });

  const [{ entries, problem }, saved] = await Promise.all([loadPanelList(robotName, robotPath), loadSavedLayout()]);
  if (problem) showPageError(root, problem);
  const kinds = [...new Set(entries.filter((entry) => entry.ok).map((entry) => entry.descriptor.kind))];
  const modules = new Map(await Promise.all(kinds.map((kind) => import(PANEL_REGISTRY[kind].module)
    .then((module) => [kind, module], (error) => [kind, error]))));
  root.querySelector("[data-console-loading]")?.remove();
  for (const entry of entries) {
    if (!entry.ok) {
      layout.addNotice(`${entry.title ? `The panel “${entry.title}”` : "A panel"} could not be shown: ${entry.problem}.`);
      continue;
    }
    const { descriptor } = entry;
    const { tag, span } = PANEL_REGISTRY[descriptor.kind];
    const module = modules.get(descriptor.kind);
    try {
      if (module instanceof Error) throw new Error(`its code did not load (${module.message})`);
      module.register();
      const panel = h(tag, { "data-panel-id": descriptor.id });
      layout.addPanel(descriptor, panel, span);
      wiring.wire(descriptor, panel);
    } catch (error) {
      layout.addNotice(`The panel “${descriptor.title}” could not be started: ${error.message}.`);
    }
  }
  layout.restore(saved);
  wiring.startAll();
}

start();
