// The maps' feed services: "map-grid" (the map panel: the occupancy grid and, when there is none, why), "map-view"
// (another view of the grid, the 3D lab view's), "goal-target" (a map picks targets for the skill with goal x/y
// parameters, starts it, clears the map, returns the robot to its dock) and "goal-view" (a view that shows goals
// without picking them). The grid is polled once for all of a console's readers, every MAP_POLL_MS while one is in
// view; the goals' feedback comes from the wiring's "goal-feedback" (skill-goals.js), the control from its "seat".

import { fetchJson } from "../transport.js";
import { perConsole, registerFeedService } from "./feed-services.js";
import { aimGoalSkill, hasGoalSkill, startGoalSkill } from "./skill-goals.js";
import { t } from "../i18n.js";

const MAP_POLL_MS = 2000;
const ACTION_NOTE_MS = 10000; // "back at its dock" stays this long before the map's polls speak again

const mapsOf = perConsole((wiring) => {
  const maps = { readers: [], pickers: [], goalViews: [], lastCells: null, actionNoteUntil: 0 };
  // Feedback of the goal skill's goals (its goal, planned path, obstacle values) is drawn on every map and view.
  wiring.addEventListener("goal-feedback", ({ detail }) => {
    for (const view of [...maps.pickers, ...maps.goalViews]) view.goalFeedback = detail;
  });
  return maps;
});

/** One more panel showing the occupancy grid; the grid is polled (once for all of them) while one is shown. */
function readMap(wiring, descriptor, { take, fail = () => {} }) {
  const maps = mapsOf(wiring);
  let visible = true;
  const frame = wiring.layout.frameOf(descriptor.id);
  new IntersectionObserver((entries) => { visible = entries.some((e) => e.isIntersecting); }).observe(frame);
  const shown = () => visible && wiring.layout.isShown(descriptor.id);
  if (!maps.readers.length) {
    wiring.onStart(() => {
      pollMap(wiring);
      setInterval(() => pollMap(wiring), MAP_POLL_MS);
    });
  }
  maps.readers.push({ id: descriptor.id, shown, take, fail });
}

async function pollMap(wiring) {
  const maps = mapsOf(wiring);
  if (document.visibilityState !== "visible" || !maps.readers.some((reader) => reader.shown())) return;
  try {
    const answer = await fetchJson(`/api/robots/${encodeURIComponent(wiring.robotName)}/map`);
    const grid = answer?.map ?? null;
    const changed = grid?.cells_b64 !== maps.lastCells;
    maps.lastCells = grid?.cells_b64;
    for (const reader of maps.readers) wiring.guard(reader.id, () => reader.take(grid, answer, changed));
  } catch (error) {
    maps.lastCells = null;
    for (const reader of maps.readers) reader.fail(error);
  }
}

/** The map panel: the occupancy grid and, when there is none, why. */
export function connectMapGrid(wiring, descriptor, panel) {
  const maps = mapsOf(wiring);
  readMap(wiring, descriptor, {
    take: (grid, answer, changed) => {
      if (Date.now() >= maps.actionNoteUntil) panel.note = grid ? "" : String(answer?.message ?? "");
      if (changed) panel.grid = grid;
    },
    fail: (error) => {
      panel.grid = null;
      // A map withheld during an obstacle-zone test is no fault: its sentence says why and until when.
      panel.note = error.code === "obstacles_hidden" ? error.message : t("The map could not be loaded: {message}", { message: error.message });
    },
  });
}

/** Another view of the grid: the grid alone, when it changed. */
export function connectMapView(wiring, descriptor, panel) {
  readMap(wiring, descriptor, { take: (grid, answer, changed) => { if (changed) panel.map = grid; } });
}

/** Shows an action's answer on the map, kept over the polls' notes long enough to be read. */
function actionNote(wiring, mapPanel, text) {
  mapsOf(wiring).actionNoteUntil = Date.now() + ACTION_NOTE_MS;
  mapPanel.note = text;
}

/** Forgets the robot's map (the controller's command); its answer is held over the polls, then "No map yet". */
async function clearMap(wiring, mapPanel) {
  try {
    const answer = await fetchJson(`/api/robots/${encodeURIComponent(wiring.robotName)}/map`, { method: "DELETE" });
    mapPanel.grid = null;
    actionNote(wiring, mapPanel, String(answer?.message ?? "")); // then the polls' "No map yet"
  } catch (error) {
    mapPanel.note = t("The map was not cleared: {message}", { message: error.message });
  }
}

async function returnToDock(wiring, mapPanel) {
  try {
    const answer = await fetchJson(`/api/robots/${encodeURIComponent(wiring.robotName)}/dock`, { method: "POST" });
    mapPanel.resetTrails();
    actionNote(wiring, mapPanel, String(answer?.message ?? ""));
  } catch (error) {
    mapPanel.note = t("The robot was not moved: {message}", { message: error.message });
  }
}

/** A target picked on the map goes to the goal skill, and shows on that map and the goal views. */
function routeTarget(wiring, mapPanel, { x_m, y_m }) {
  if (!aimGoalSkill(wiring, x_m, y_m)) return false;
  mapPanel.target = [x_m, y_m];
  for (const view of mapsOf(wiring).goalViews) view.target = [x_m, y_m];
  return true;
}

/** A map picks targets for the skills with goal x/y parameters and shows their goals' feedback. */
export function connectGoalTarget(wiring, descriptor, panel) {
  mapsOf(wiring).pickers.push(panel);
  panel.addEventListener("map-target", ({ detail }) => routeTarget(wiring, panel, detail));
  panel.addEventListener("map-go", ({ detail }) => {
    if (routeTarget(wiring, panel, detail)) startGoalSkill(wiring, detail.x_m, detail.y_m);
  });
  panel.addEventListener("map-clear", () => clearMap(wiring, panel));
  panel.addEventListener("map-dock", () => returnToDock(wiring, panel));
  panel.supervising = wiring.root.dataset.supervisor !== undefined;
  wiring.onStart(() => { panel.canGo = hasGoalSkill(wiring); });
  wiring.addEventListener("seat", ({ detail }) => { panel.observing = !detail.is_controller; });
}

/** A view that shows the goal skill's goals (target and feedback) without picking them. */
export function connectGoalView(wiring, descriptor, panel) {
  mapsOf(wiring).goalViews.push(panel);
}

registerFeedService("map-grid", connectMapGrid);
registerFeedService("map-view", connectMapView);
registerFeedService("goal-target", connectGoalTarget);
registerFeedService("goal-view", connectGoalView);
