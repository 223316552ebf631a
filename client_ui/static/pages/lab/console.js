// The lab console page (the paper's ExperimentTool): asks the middleware which panels this robot's
// abstractions describe, places them in the order sent, and wires each to the feeds its panel module
// declared. It knows no panel's insides: the kinds come from the panels' own registrations
// (static/panels/registry.js); an unknown kind becomes a notice.

import { ApiError, fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { checkPanelList } from "../../lib/panel-descriptors.js";
import { ConsoleLayout } from "../../lib/console/console-layout.js";
import { ConsoleWiring } from "../../lib/console/console-wiring.js";
import * as connectionStatus from "../../panels/connection-status/connection-status.js";
import { loadPanels } from "../../panels/registry.js";
import { t } from "../../lib/i18n.js";

const LAYOUT_PREFERENCE = "/api/me/preferences/console-layout";

/** The panels every robot had before the middleware described them; used only if the list cannot be had. */
function basicPanels(robotPath) {
  return [
    { id: "camera", kind: "camera", title: t("Camera"), channel: `${robotPath}/camera`, tab: "drive" },
    { id: "drive", kind: "drive", title: t("Drive"), channel: `${robotPath}/drive`, tab: "drive" },
    { id: "queue", kind: "queue", title: t("Turn"), channel: `${robotPath}/queue`, tab: "drive" },
    { id: "odometry", kind: "odometry", title: t("Odometry"), channel: `${robotPath}/telemetry`, tab: "drive" },
    { id: "chat", kind: "chat", title: t("Chat"), channel: `${robotPath}/chat`, tab: "chat" },
  ];
}

function showPageError(root, text) {
  const line = root.querySelector("#console-error");
  line.textContent = text;
  line.hidden = !text;
}

/** The robot's panel list: {answer} or {error}, never a rejection (it is awaited after the panel modules load). */
function fetchPanelList(robotName) {
  return fetchJson(`/api/robots/${encodeURIComponent(robotName)}/panels`)
    .then((answer) => ({ answer }), (error) => ({ error }));
}

/** Check the answer against the registered kinds; the basic panels, with a problem, when it is unusable. A robot
 *  that does not answer gets the middleware's own panels and a notice saying why its own are missing. */
function checkedPanelList({ answer, error }, robotPath, panels) {
  const checked = error ? null : checkPanelList(answer, panels);
  if (checked) return { entries: checked, problem: typeof answer.notice === "string" ? answer.notice : "" };
  const why = error instanceof ApiError ? error.message : t("it could not be loaded");
  return { entries: checkPanelList({ panels: basicPanels(robotPath) }, panels),
    problem: error ? t("The robot's panel list is unavailable ({why}); showing the basic panels.", { why })
      : t("The robot's panel list could not be read; showing the basic panels.") };
}

/** A descriptor's problem in words, naming the panel modules that did not load when its kind is unknown. */
function describeProblem(entry, failed) {
  const modules = failed.map(({ module, problem }) => `${module}: ${problem}`).join("; ");
  return failed.length && entry.problem.startsWith(t("this console does not know"))
    ? t("{problem} (panel code that did not load: {modules})", { problem: entry.problem, modules }) : entry.problem;
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
    onSaveError: (error) => showPageError(root, t("Your panel layout was not saved: {message}", { message: error.message })),
  });
  const wiring = new ConsoleWiring({ root, robotName, robotPath, status, layout });

  const [{ panels, failed }, list, saved] = await Promise.all([loadPanels(), fetchPanelList(robotName), loadSavedLayout()]);
  for (const { module, problem } of failed) console.warn(`panel module ${module} did not load:`, problem);
  const { entries, problem } = checkedPanelList(list, robotPath, panels);
  if (problem) showPageError(root, problem);
  root.querySelector("[data-console-loading]")?.remove();
  for (const entry of entries) {
    if (!entry.ok) {
      layout.addNotice(t("{value} could not be shown: {entry}.", { value: entry.title ? t("The panel “{title}”", { title: entry.title }) : t("A panel"), entry: describeProblem(entry, failed) }));
      continue;
    }
    const { descriptor } = entry;
    const { tag, span, feeds, register } = panels.get(descriptor.kind);
    try {
      register();
      const panel = h(tag, { "data-panel-id": descriptor.id });
      layout.addPanel(descriptor, panel, span);
      wiring.wire(descriptor, panel, feeds);
    } catch (error) {
      layout.addNotice(t("The panel “{title}” could not be started: {message}.", { title: descriptor.title, message: error.message }));
    }
  }
  layout.restore(saved);
  wiring.startAll();
}

start();
