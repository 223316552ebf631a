// A robot's own console panels on a teaching page (the panels a tour names, a lesson's camera and map): the
// panel registry and the console's layout and wiring, for the few panels the page asks for, so a panel
// changed for the console is the same here. The page keeps its own text; this module only places panels.
import { h } from "../dom.js";
import { fetchJson } from "../transport.js";
import { checkPanelList } from "../panel-descriptors.js";
import { loadPanels } from "../../panels/registry.js";
import * as connectionStatus from "../../panels/connection-status/connection-status.js";
import { ConsoleLayout } from "./console-layout.js";
import { ConsoleWiring } from "./console-wiring.js";
import { t } from "../i18n.js";

/** A panel id in words when the robot does not describe it ("skill-wall_following" -> "Wall following"). */
export function panelWords(id) {
  const words = String(id ?? "").replace(/^skill-/, "").replace(/[_-]+/g, " ").trim();
  return words ? words[0].toUpperCase() + words.slice(1) : "–";
}

/**
 * Show robotName's panels whose ids are in `wanted` (in the robot's order) inside host.
 * Returns {titles: Map id -> title of every panel the robot has, shown: Set of the ids placed, highlight(id)};
 * never rejects.
 */
export async function showRobotPanels(host, robotName, wanted) {
  connectionStatus.register();
  const status = h("connection-status");
  const online = h("p", { class: "badge", id: "robot-online", "data-field": "robot-online", text: t("Checking…") });
  const problem = h("p", { class: "alert alert--error", id: "console-error", role: "alert", hidden: true });
  const grid = h("div", { class: "console__panels", "data-slot": "panels" });
  host.replaceChildren(h("div", { class: "robot-panels__bar" }, online, status), problem, grid);
  status.robotName = robotName;
  const robotPath = `/ws/robots/${encodeURIComponent(robotName)}`;
  const layout = new ConsoleLayout(grid, h("div"), { tabs: false });
  const wiring = new ConsoleWiring({ root: host, robotName, robotPath, status, layout });
  const titles = new Map();
  const shown = new Set();
  try {
    const [{ panels }, answer] = await Promise.all([loadPanels(),
      fetchJson(`/api/robots/${encodeURIComponent(robotName)}/panels`)]);
    if (typeof answer?.notice === "string" && answer.notice) {
      problem.textContent = answer.notice; // the robot does not answer: only the middleware's own panels came
      problem.hidden = false;
    }
    for (const entry of checkPanelList(answer, panels) ?? []) {
      if (!entry.ok) continue;
      const { descriptor } = entry;
      titles.set(descriptor.id, descriptor.title);
      if (!wanted.includes(descriptor.id)) continue;
      const { tag, span, feeds, register } = panels.get(descriptor.kind);
      register();
      const panel = h(tag, { "data-panel-id": descriptor.id });
      layout.addPanel(descriptor, panel, span);
      shown.add(descriptor.id);
      wiring.wire(descriptor, panel, feeds);
    }
    layout.restore(null);
    wiring.startAll();
  } catch (error) {
    problem.textContent = t("The robot's panels could not be shown: {message}", { message: error.message });
    problem.hidden = false;
  }
  return {
    titles,
    shown,
    highlight(id) {
      for (const frame of grid.querySelectorAll(".panel-frame")) {
        frame.classList.toggle("panel-frame--current", frame.dataset.panelId === id);
      }
      // The step points at it: it comes into view (the least scroll that shows it, its title first when it is
      // taller than the screen), never left below the fold.
      const current = grid.querySelector(".panel-frame--current");
      const box = current?.getBoundingClientRect();
      if (box && (box.top < 0 || box.bottom > innerHeight)) {
        current.scrollIntoView({ block: box.height > innerHeight ? "start" : "nearest", behavior: "smooth" });
      }
    },
  };
}

/** The words for "look at" a step's panel: its title on this robot, or the id in words. */
export function panelTitle(titles, id) {
  return titles.get(id) ?? panelWords(id);
}
