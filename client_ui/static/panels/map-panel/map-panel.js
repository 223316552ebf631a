// <map-panel>: the lab model in 2D. The floor plan is in true coordinates, so each pose is drawn in its
// own labelled style with a trail: odometry (drifts), the localized estimate (while localization runs),
// else the pose the skills steer by when the robot tracks it against the floor plan, and the true pose (only
// when the server sends it, i.e. where the teaching mode allows). The gap between odometry and the best other
// pose is drawn as the drift. Laser hits and sonar cones are placed by the robot's best belief (the estimate,
// else the tracked pose, else odometry), and the legend names which; it lists only
// what is drawn. Click, tap or keyboard (arrows move a cursor, Enter sets it) picks a target; "Go there"
// asks for a go-to-goal to it.
// In: `info` (robot info: scene_boxes, sonars, laser, body_radius_m), `telemetry`, `localization`,
//     `grid` (the map answer or null), `goalFeedback` (go-to-goal feedback, for its goal, values and planned path),
//     `target` ([x_m, y_m] or null), `note` (a sentence about the map's data), `canGo` (a goal skill exists),
//     `observing` (someone else has the turn: "Go there" is off), `supervising` (a tutor or an admin: clearing the
//     map and the return to the dock stay on while observing).
// Out: "map-target" and "map-go" (detail {x_m, y_m}), "map-clear" (forget the map, after confirming: it is the
//      robot's map for everyone after), "map-dock" (carry the robot back to its dock, after confirming).

import { h } from "../../lib/dom.js";
import {
  boxCorners, canvasToWorld, extendTrail, fitView, laserHits, moveCursor, poseDistance, sceneBounds, sonarCone,
  worldToCanvas, worldTransform,
} from "../../lib/map-geometry.js";
import { isEcho } from "../../lib/polar.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed as localFixed, t } from "../../lib/i18n.js";

const CURSOR_STEP_M = 0.1;
const COLOURS = {
  box: "#5b6778", odometry: "#1d5fc4", localized: "#7a3bb8", truth: "#17703a", laser: "#d1390f",
  sonar: "rgb(194 106 0 / 7%)", particle: "rgb(122 59 184 / 55%)", target: "#b1261b", cursor: "#c26a00",
  drift: "#2b2f36",
};
const POSE_STYLES = {
  odometry: { colour: COLOURS.odometry, label: t("odometry"), dash: [], filled: true },
  localized: { colour: COLOURS.localized, label: t("estimate"), dash: [6, 4], filled: false },
  tracked: { colour: COLOURS.localized, label: t("tracked"), dash: [6, 4], filled: false },
  truth: { colour: COLOURS.truth, label: t("true"), dash: [2, 3], filled: false },
};
// The legend's entries: [colour, text, swatch shape]; render() lists those it drew.
const LEGEND = {
  odometry: [COLOURS.odometry, t("odometry pose (from the wheels; it drifts)"), "robot"],
  localized: [COLOURS.localized, t("localized estimate"), "robot-dashed"],
  tracked: [COLOURS.localized, t("tracked pose the skills steer by (laser against the floor plan)"), "robot-dashed"],
  truth: [COLOURS.truth, t("true pose"), "robot-dotted"],
  trail: ["#7b8494", t("trail of where it has been"), "line"],
  drift: [COLOURS.drift, t("drift of odometry"), "line-dashed"],
  "laser-odometry": [COLOURS.laser, t("laser hits, placed by the odometry pose"), "dot"],
  "laser-localized": [COLOURS.laser, t("laser hits, placed by the localized estimate"), "dot"],
  "laser-tracked": [COLOURS.laser, t("laser hits, placed by the tracked pose"), "dot"],
  sonar: ["#c26a00", t("sonar cones"), "cone"],
  particles: [COLOURS.particle, t("localization particles"), "dot"],
  target: [COLOURS.target, "target", "cross"],
  path: [COLOURS.target, t("path planned to the goal"), "line-dashed"],
  grid: ["#444", t("occupancy map"), "cell"],
};

// A number for code to read (a data attribute): always with a decimal point.
function plain(value, decimals = 2) {
  const number = Number(value);
  if (!Number.isFinite(number)) return "—";
  const text = number.toFixed(decimals); // data, not text: a data attribute code reads
  return Number(text) === 0 ? (0).toFixed(decimals) : text; // data, not text: no "-0.00"
}

// A number a person reads: as plain() rounds it, with the page's language's decimal sign ("0,25" in Spanish).
function fixed(value, decimals = 2) {
  const text = plain(value, decimals);
  return text === "—" ? text : localFixed(Number(text), decimals);
}

function isPose(pose) {
  return pose && [pose.x_m, pose.y_m, pose.theta_rad].every((v) => Number.isFinite(Number(v)));
}

/** The offscreen image of an occupancy grid: one pixel per cell, row 0 = lowest y. Built once per map. */
export function gridImage(grid) {
  const width = Number(grid.width_cells);
  const height = Number(grid.height_cells);
  const bytes = Uint8Array.from(atob(grid.cells_b64), (c) => c.charCodeAt(0));
  if (!(width > 0 && height > 0) || bytes.length < width * height) throw new Error("the map's size and cells disagree");
  const image = new ImageData(width, height);
  for (let i = 0; i < width * height; i += 1) {
    const value = bytes[i];
    const o = i * 4;
    if (value === 255) {
      image.data[o + 3] = 0; // unknown: transparent
      continue;
    }
    // Free space (below 50 %) is white on the grey unknown background; occupied cells darken with belief.
    const shade = value < 50 ? 255 : Math.round(200 - ((Math.min(100, value) - 50) / 50) * 170);
    image.data[o] = shade;
    image.data[o + 1] = shade;
    image.data[o + 2] = value < 50 ? 255 : shade;
    image.data[o + 3] = value < 50 ? 235 : 255;
  }
  const canvas = document.createElement("canvas");
  canvas.width = width;
  canvas.height = height;
  canvas.getContext("2d").putImageData(image, 0, 0);
  return canvas;
}

export class MapPanel extends PanelElement {
  #canvas;
  #summary;
  #cursorLine;
  #info = null;
  #telemetry = null;
  #localization = null;
  #grid = null;
  #gridCanvas = null;
  #feedback = null;
  #target = null;
  #cursor = null;
  #bounds = sceneBounds([]);
  #trails = { odometry: [], localized: [], tracked: [], truth: [] };
  #legend;
  #legendKeys = "";
  #go;
  #clear;
  #dock;
  #observing = false;
  #supervising = false;
  #view = null;
  #resizeObserver = null;

  connectedCallback() {
    super.connectedCallback();
    this.#resizeObserver ??= new ResizeObserver(() => this.scheduleRender());
    this.#resizeObserver.observe(this.#canvas);
  }

  disconnectedCallback() {
    super.disconnectedCallback();
    this.#resizeObserver?.disconnect();
  }

  set info(info) {
    this.ensureBuilt();
    this.#info = info ?? null;
    this.#bounds = sceneBounds(Array.isArray(info?.scene_boxes) ? info.scene_boxes : []);
    this.scheduleRender();
  }

  set telemetry(message) {
    this.#telemetry = message;
    this.#extendTrails();
    this.scheduleRender();
  }

  set localization(message) {
    this.#localization = message?.type === "localization" ? message : null;
    this.#extendTrails();
    this.scheduleRender();
  }

  set observing(observing) {
    this.ensureBuilt();
    this.#observing = Boolean(observing);
    this.#go.disabled = this.#observing || !this.#target;
    this.#updateSupervision();
    this.#go.title = this.#observing ? t("Going there waits for your turn") : t("Start go-to-goal to the target picked on the map");
  }

  /** Whether the user may clear the map and dock the robot while observing (a tutor or an admin). */
  set supervising(supervising) {
    this.ensureBuilt();
    this.#supervising = Boolean(supervising);
    this.#updateSupervision();
  }

  /** Forgets the trails (the robot was carried elsewhere: a line to its new place would be a lie). */
  resetTrails() {
    this.#trails = { odometry: [], localized: [], tracked: [], truth: [] };
    this.scheduleRender();
  }

  #updateSupervision() {
    const off = this.#observing && !this.#supervising;
    for (const button of [this.#clear, this.#dock]) {
      button.disabled = off;
      button.title = off ? t("This waits for your turn (or a tutor)") : button.dataset.title;
    }
  }

  /** Whether the robot has a goal skill that "Go there" can start. */
  set canGo(available) {
    this.ensureBuilt();
    this.#go.hidden = !available;
  }

  /** The occupancy grid answer, or null when there is no map yet. */
  set grid(grid) {
    this.ensureBuilt();
    this.#clear.hidden = !grid;
    if (!grid) {
      this.#grid = null;
      this.#gridCanvas = null;
    } else if (grid !== this.#grid) {
      this.#gridCanvas = gridImage(grid); // may throw on a malformed map; the console shows a notice
      this.#grid = grid;
    }
    this.scheduleRender();
  }

  set goalFeedback(feedback) {
    this.#feedback = feedback ?? null;
    this.scheduleRender();
  }

  set target(target) {
    this.ensureBuilt();
    this.#target = Array.isArray(target) ? target : null;
    this.#go.disabled = this.#observing || !this.#target;
    this.scheduleRender();
  }

  /** A sentence about the map itself (none yet, could not be loaded), or "" to clear it. */
  set note(text) {
    this.showMessage(text);
  }

  build() {
    this.classList.add("panel", "map");
    this.#canvas = h("canvas", {
      class: "map__canvas", width: 480, height: 360, tabindex: "0", role: "application",
      "data-wants-arrow-keys": "", "data-field": "map-canvas",
      "aria-label": t("Lab map. Click or tap to set a go-to-goal target; with the keyboard, arrow keys move a cursor and Enter sets the target."),
      "aria-describedby": "map-summary",
    });
    this.#canvas.addEventListener("click", (event) => this.#onClick(event));
    this.#canvas.addEventListener("keydown", (event) => this.#onKey(event));
    this.#canvas.addEventListener("focus", () => this.scheduleRender());
    this.#canvas.addEventListener("blur", () => this.scheduleRender());
    this.#summary = h("p", { class: "map__summary", id: "map-summary", "data-field": "map-summary", text: t("Waiting for the robot…") });
    this.#cursorLine = h("p", { class: "map__cursor", "aria-live": "polite", "data-field": "map-cursor" });
    this.#go = h("button", {
      type: "button", class: "button button--primary map__go", "data-action": "go-there", disabled: true, hidden: true,
      text: t("Go there"), title: t("Start go-to-goal to the target picked on the map"),
      onclick: () => this.#target && this.emit("map-go", { x_m: this.#target[0], y_m: this.#target[1] }),
    });
    this.#clear = h("button", {
      type: "button", class: "button button--secondary map__clear", "data-action": "clear-map", hidden: true,
      text: t("Clear the map"), "data-title": t("Forget this robot's map (for everyone) and start a new one"),
      onclick: () => {
        if (window.confirm(t("Clear this robot's map? Everyone using the robot after you starts from no map."))) {
          this.emit("map-clear", {});
        }
      },
    });
    this.#dock = h("button", {
      type: "button", class: "button button--secondary map__dock", "data-action": "dock",
      text: t("Return to the dock"),
      "data-title": t("Carry the robot back to its dock: its skills stop and its odometry restarts there"),
      onclick: () => {
        if (window.confirm(t("Carry the robot back to its dock? Its running skills stop; the map is kept."))) {
          this.emit("map-dock", {});
        }
      },
    });
    this.#updateSupervision();
    this.#legend = h("ul", { class: "map__legend", "aria-label": t("Map legend"), "data-field": "map-legend" });
    this.append(
      h("h2", { class: "panel__title", text: t("Lab model") }),
      h("div", { class: "map__stage" }, this.#canvas),
      h("div", { class: "map__actions" }, this.#cursorLine, this.#go, this.#clear, this.#dock),
      this.#summary,
      this.messageLine({ class: "map__note muted", "data-field": "map-note" }),
      this.#legend,
    );
  }

  #extendTrails() {
    const poses = this.#poses();
    for (const frame of Object.keys(this.#trails)) {
      this.#trails[frame] = poses[frame] ? extendTrail(this.#trails[frame], poses[frame]) : [];
    }
  }

  /** Lists exactly the layers the last render drew (rebuilt only when that set changes). */
  #showLegend(layers) {
    const keys = layers.join(" ");
    if (keys === this.#legendKeys) return;
    this.#legendKeys = keys;
    this.#legend.replaceChildren(...layers.map((layer) => {
      const [colour, text, shape] = LEGEND[layer];
      const swatch = h("span", { class: `map__swatch map__swatch--${shape}`, "aria-hidden": "true" });
      swatch.style.setProperty("--swatch", colour); // CSSOM, not a style attribute: the CSP allows it
      return h("li", { "data-layer": layer }, swatch, text);
    }));
  }

  #poses() {
    const odometry = this.#telemetry?.odometry?.pose;
    const loc = this.#localization;
    const localized = loc?.active && isPose(loc.estimate) ? loc.estimate : null;
    // Without the localization skill, the navigation stack's own tracking against the floor plan (if it has one).
    const navigation = loc?.navigation;
    const tracked = !localized && navigation?.source === "map tracking" && isPose(navigation.pose) ? navigation.pose : null;
    return {
      odometry: isPose(odometry) ? odometry : isPose(loc?.odometry) ? loc.odometry : null,
      localized,
      tracked,
      truth: isPose(loc?.ground_truth) ? loc.ground_truth : null,
    };
  }

  render() {
    const canvas = this.#canvas;
    const ratio = window.devicePixelRatio || 1;
    // The CSS box decides the shape (a fixed ratio, capped by the window's height); the drawing fits into it.
    const cssWidth = canvas.clientWidth || 480;
    const width = Math.round(cssWidth * ratio);
    const height = Math.round((canvas.clientHeight || cssWidth * 0.72) * ratio);
    if (canvas.width !== width || canvas.height !== height) {
      canvas.width = width;
      canvas.height = height;
    }
    const view = fitView(this.#bounds, width, height, 10 * ratio);
    this.#view = { ...view, ratio };
    const ctx = canvas.getContext("2d");
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = this.#gridCanvas ? "#e4e8ee" : "#f7f9fb"; // with a map, grey means "not seen yet"
    ctx.fillRect(0, 0, width, height);
    ctx.setTransform(...worldTransform(view));
    const px = 1 / view.scale; // one device pixel in metres

    const drawn = new Set();
    if (this.#gridCanvas && this.#grid) {
      drawn.add("grid");
      ctx.imageSmoothingEnabled = false;
      const res = Number(this.#grid.resolution_m);
      ctx.drawImage(this.#gridCanvas, Number(this.#grid.origin_x_m), Number(this.#grid.origin_y_m),
        this.#grid.width_cells * res, this.#grid.height_cells * res);
    }
    this.#drawGridLines(ctx, px);
    ctx.fillStyle = COLOURS.box;
    for (const box of this.#info?.scene_boxes ?? []) {
      this.#polygon(ctx, boxCorners(box));
      ctx.fill();
    }
    const poses = this.#poses();
    // Readings are drawn where the robot believes it is: the localized pose once localization runs, else the
    // tracked one, else odometry.
    const believed = ["localized", "tracked", "odometry"].find((frame) => poses[frame]);
    if (believed) {
      for (const layer of this.#drawSensors(ctx, poses[believed], px)) {
        drawn.add(layer === "laser" ? `laser-${believed}` : layer);
      }
    }
    for (const particle of (this.#localization?.particles ?? []).slice(0, 3000)) {
      if (!Array.isArray(particle)) continue;
      drawn.add("particles");
      ctx.fillStyle = COLOURS.particle;
      ctx.fillRect(particle[0] - 1.5 * px, particle[1] - 1.5 * px, 3 * px, 3 * px);
    }
    const radius = Number(this.#info?.body_radius_m) || 0.2;
    const frames = ["truth", "localized", "tracked", "odometry"].filter((frame) => poses[frame]);
    for (const frame of frames) {
      if (this.#drawTrail(ctx, this.#trails[frame], POSE_STYLES[frame], px)) drawn.add("trail");
    }
    const reference = poses.truth ?? poses.localized ?? poses.tracked;
    if (poses.odometry && reference) {
      drawn.add("drift");
      ctx.strokeStyle = COLOURS.drift;
      ctx.lineWidth = 1.5 * px;
      ctx.setLineDash([4 * px, 3 * px]);
      ctx.beginPath();
      ctx.moveTo(poses.odometry.x_m, poses.odometry.y_m);
      ctx.lineTo(reference.x_m, reference.y_m);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    for (const frame of frames) {
      drawn.add(frame);
      this.#drawRobot(ctx, poses[frame], radius, POSE_STYLES[frame], px);
    }

    const values = this.#feedback?.values ?? {};
    const goal = this.#target ?? (Number.isFinite(values.goal_x_m) && Number.isFinite(values.goal_y_m)
      ? [values.goal_x_m, values.goal_y_m] : null);
    if (goal) {
      drawn.add("target");
      this.#cross(ctx, goal, COLOURS.target, 7 * px, 2.5 * px);
    }
    if (this.#drawPlannedPath(ctx, px)) drawn.add("path");
    if (Number.isFinite(values.obstacle_x_m) && Number.isFinite(values.obstacle_y_m)) {
      ctx.strokeStyle = COLOURS.target;
      ctx.lineWidth = 2 * px;
      ctx.beginPath();
      ctx.arc(values.obstacle_x_m, values.obstacle_y_m, 8 * px, 0, 2 * Math.PI);
      ctx.stroke();
    }
    if (this.#cursor && document.activeElement === this.#canvas) {
      this.#cross(ctx, this.#cursor, COLOURS.cursor, 9 * px, 2 * px);
    }
    this.#labelPoses(ctx, view, poses, frames, radius);
    this.#showLegend(Object.keys(LEGEND).filter((layer) => drawn.has(layer)));
    this.#summarize(poses, goal);
  }

  /** Each pose's name beside its glyph, so the frames are told apart without the legend. */
  #labelPoses(ctx, view, poses, frames, radius) {
    const ratio = this.#view.ratio;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.font = `${Math.round(11 * ratio)}px system-ui, sans-serif`;
    ctx.textBaseline = "middle";
    frames.forEach((frame, index) => {
      const [x, y] = worldToCanvas(view, poses[frame].x_m, poses[frame].y_m);
      ctx.fillStyle = POSE_STYLES[frame].colour;
      // Stacked labels: the poses are often within a few pixels of each other.
      const row = index - (frames.length - 1) / 2;
      ctx.fillText(POSE_STYLES[frame].label, x + radius * view.scale + 6 * ratio, y + row * 13 * ratio);
    });
  }

  #drawTrail(ctx, trail, style, px) {
    if (trail.length < 2) return false;
    ctx.strokeStyle = style.colour;
    ctx.globalAlpha = 0.55;
    ctx.lineWidth = 1.5 * px;
    ctx.setLineDash(style.dash.map((length) => length * px));
    ctx.beginPath();
    trail.forEach(([x, y], index) => (index ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.globalAlpha = 1;
    return true;
  }

  /** The go-to-goal path still ahead, dashed, from the pose the skill steers by; whether there was one. */
  #drawPlannedPath(ctx, px) {
    const feedback = this.#feedback;
    const waypoints = Array.isArray(feedback?.planned_path) ? feedback.planned_path : [];
    const start = isPose(feedback?.pose) ? [[feedback.pose.x_m, feedback.pose.y_m]] : [];
    const points = [...start, ...waypoints].map((point) => (Array.isArray(point) ? point.map(Number) : []))
      .filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
    if (!waypoints.length || points.length < 2) return false;
    ctx.strokeStyle = COLOURS.target;
    ctx.lineWidth = 2 * px;
    ctx.setLineDash([6 * px, 4 * px]);
    ctx.beginPath();
    points.forEach(([x, y], index) => (index ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.stroke();
    ctx.setLineDash([]);
    return true;
  }

  #drawGridLines(ctx, px) {
    const b = this.#bounds;
    ctx.strokeStyle = "#e2e7ee";
    ctx.lineWidth = px;
    ctx.beginPath();
    for (let x = Math.ceil(b.minX); x <= b.maxX; x += 1) { ctx.moveTo(x, b.minY); ctx.lineTo(x, b.maxY); }
    for (let y = Math.ceil(b.minY); y <= b.maxY; y += 1) { ctx.moveTo(b.minX, y); ctx.lineTo(b.maxX, y); }
    ctx.stroke();
  }

  /** Draws the sonar cones and laser hits that have echoes; returns the layers drawn ("sonar", "laser"). */
  #drawSensors(ctx, pose, px) {
    const layers = [];
    const sonars = Array.isArray(this.#info?.sonars) ? this.#info.sonars : [];
    const ranges = this.#telemetry?.sonar?.ranges_m ?? [];
    ctx.fillStyle = COLOURS.sonar;
    sonars.forEach((sonar, index) => {
      const range = ranges[index];
      if (!isEcho(range, Number(sonar.max_range_m) || Infinity)) return;
      if (!layers.includes("sonar")) layers.push("sonar");
      this.#polygon(ctx, sonarCone(pose, sonar, range));
      ctx.fill();
    });
    const hits = laserHits(pose, this.#telemetry?.laser, Number(this.#info?.laser?.max_range_m) || Infinity);
    if (hits.length) layers.push("laser");
    ctx.fillStyle = COLOURS.laser;
    for (const [x, y] of hits) ctx.fillRect(x - 1.5 * px, y - 1.5 * px, 3 * px, 3 * px);
    return layers;
  }

  #drawRobot(ctx, pose, radius, style, px) {
    ctx.lineWidth = 2.5 * px;
    ctx.strokeStyle = style.colour;
    ctx.fillStyle = `${style.colour}40`;
    ctx.setLineDash(style.dash.map((length) => length * px));
    ctx.beginPath();
    ctx.arc(pose.x_m, pose.y_m, radius, 0, 2 * Math.PI);
    if (style.filled) ctx.fill();
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.beginPath();
    ctx.moveTo(pose.x_m, pose.y_m);
    ctx.lineTo(pose.x_m + Math.cos(pose.theta_rad) * radius * 1.4, pose.y_m + Math.sin(pose.theta_rad) * radius * 1.4);
    ctx.stroke();
  }

  #polygon(ctx, points) {
    ctx.beginPath();
    points.forEach(([x, y], index) => (index ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.closePath();
  }

  #cross(ctx, [x, y], colour, size, width) {
    ctx.strokeStyle = colour;
    ctx.lineWidth = width;
    ctx.beginPath();
    ctx.moveTo(x - size, y - size); ctx.lineTo(x + size, y + size);
    ctx.moveTo(x - size, y + size); ctx.lineTo(x + size, y - size);
    ctx.stroke();
  }

  #summarize(poses, goal) {
    const parts = [];
    if (poses.odometry) parts.push(t("Robot at ({x_m}, {y_m}) m by odometry", { x_m: fixed(poses.odometry.x_m), y_m: fixed(poses.odometry.y_m) }));
    const loc = this.#localization;
    if (poses.localized) {
      // "Localized" only once it converged: before, the localization panel may be saying the guess does not fit.
      const at = t("({x_m}, {y_m}) m", { x_m: fixed(poses.localized.x_m), y_m: fixed(poses.localized.y_m) });
      parts.push((loc.converged ? t("localized at {at}, converged", { at }) : t("estimate at {at}, not converged yet", { at }))
        + (Number.isFinite(loc.position_error_m) ? t(", {position_error_m} m from the true pose", { position_error_m: fixed(loc.position_error_m, 2) }) : ""));
    }
    if (poses.tracked) {
      parts.push(t("the skills steer by ({x_m}, {y_m}) m, tracked against the floor plan",
        { x_m: fixed(poses.tracked.x_m), y_m: fixed(poses.tracked.y_m) }));
    }
    if (poses.odometry && poses.truth) {
      parts.push(t("odometry has drifted {value} m from the true pose", { value: fixed(poseDistance(poses.odometry, poses.truth)) }));
    } else if (poses.odometry && (poses.localized ?? poses.tracked)) {
      const other = poses.localized ? t("estimate") : t("tracked pose");
      parts.push(t("odometry is {value} m from the {other}", { value: fixed(poseDistance(poses.odometry, poses.localized ?? poses.tracked)), other }));
    }
    if (goal) parts.push(t("target ({value}, {value2}) m", { value: fixed(goal[0]), value2: fixed(goal[1]) }));
    if (this.#grid) parts.push(t("map of {value} scans", { value: this.#grid.scans_integrated ?? 0 })); // else the note says why not
    const text = parts.length ? `${parts.join("; ")}.` : t("Waiting for the robot…");
    if (this.#summary.textContent !== text) this.#summary.textContent = text;
  }

  #emitTarget(x_m, y_m) {
    this.#target = [x_m, y_m];
    this.#cursorLine.textContent = t("Target set to ({x_m}, {y_m}) m.", { x_m: fixed(x_m), y_m: fixed(y_m) });
    this.dataset.targetX = plain(x_m);
    this.dataset.targetY = plain(y_m);
    this.emit("map-target", { x_m, y_m });
    this.scheduleRender();
  }

  #onClick(event) {
    if (!this.#view) return;
    const rect = this.#canvas.getBoundingClientRect();
    const px = ((event.clientX - rect.left) / rect.width) * this.#canvas.width;
    const py = ((event.clientY - rect.top) / rect.height) * this.#canvas.height;
    const [x, y] = canvasToWorld(this.#view, px, py);
    this.#cursor = [x, y];
    this.#emitTarget(x, y);
  }

  #onKey(event) {
    const moves = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, 1], ArrowDown: [0, -1] };
    if (event.key in moves) {
      event.preventDefault(); // the arrows move the cursor here, not the robot
      const step = event.shiftKey ? CURSOR_STEP_M * 5 : CURSOR_STEP_M;
      const start = this.#cursor ?? this.#target ?? (this.#poses().odometry
        ? [this.#poses().odometry.x_m, this.#poses().odometry.y_m] : [0, 0]);
      const [dx, dy] = moves[event.key];
      this.#cursor = moveCursor(start, dx * step, dy * step, this.#bounds);
      this.#cursorLine.textContent = t("Cursor at ({value}, {value2}) m; Enter sets the target.", { value: fixed(this.#cursor[0]), value2: fixed(this.#cursor[1]) });
      this.scheduleRender();
    } else if (event.key === "Enter" && this.#cursor) {
      event.preventDefault();
      this.#emitTarget(...this.#cursor);
    }
  }

  /** The canvas point (CSS pixels from its top-left) of a world point; for tests and tools. */
  cssPointOf(x_m, y_m) {
    if (!this.#view) return null;
    const [px, py] = worldToCanvas(this.#view, x_m, y_m);
    const rect = this.#canvas.getBoundingClientRect();
    return [(px / this.#canvas.width) * rect.width, (py / this.#canvas.height) * rect.height];
  }
}

export const register = registerPanel({
  kind: "map", tag: "map-panel", element: MapPanel, span: 2, stylesheets: [new URL("./map-panel.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry" } },
    { socket: "localization", messages: { localization: "localization" } },
    { robotInfo: "info" },
    { service: "map-grid" },
    { service: "goal-target" },
  ],
});
