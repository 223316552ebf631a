// <map-panel>: the lab model in 2D. Scene boxes, the robot (odometry pose, localized pose, ground truth
// when the server sends it), laser hits and sonar cones, the occupancy grid, localization particles and
// the go-to-goal target. Click, tap or keyboard (arrows move a cursor, Enter sets it) picks a target.
// In: `info` (robot info: scene_boxes, sonars, laser, body_radius_m), `telemetry`, `localization`,
//     `grid` (the map answer or null), `goalFeedback` (go-to-goal feedback, for its goal and values),
//     `target` ([x_m, y_m] or null), `note` (a sentence about the map's data).
// Out: "map-target" (detail {x_m, y_m}).

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";
import {
  boxCorners, canvasToWorld, fitView, laserHits, moveCursor, sceneBounds, sonarCone, worldToCanvas, worldTransform,
} from "../../js/map-geometry.js";
import { isEcho } from "../../js/polar.js";

const CURSOR_STEP_M = 0.1;
const COLOURS = {
  box: "#5b6778", odometry: "#1d5fc4", localized: "#7a3bb8", truth: "#17703a", laser: "#d1390f",
  sonar: "rgb(194 106 0 / 7%)", particle: "rgb(122 59 184 / 55%)", target: "#b1261b", cursor: "#c26a00",
};

function fixed(value, decimals = 2) {
  const number = Number(value);
  if (!Number.isFinite(number)) return "—";
  const text = number.toFixed(decimals);
  return Number(text) === 0 ? (0).toFixed(decimals) : text; // no "-0.00"
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

export class MapPanel extends HTMLElement {
  #built = false;
  #canvas;
  #summary;
  #cursorLine;
  #noteLine;
  #info = null;
  #telemetry = null;
  #localization = null;
  #grid = null;
  #gridCanvas = null;
  #feedback = null;
  #target = null;
  #cursor = null;
  #bounds = sceneBounds([]);
  #view = null;
  #frame = 0;
  #resizeObserver = null;

  connectedCallback() {
    this.#build();
    this.#resizeObserver ??= new ResizeObserver(() => this.#redraw());
    this.#resizeObserver.observe(this.#canvas);
  }

  disconnectedCallback() {
    this.#resizeObserver?.disconnect();
    cancelAnimationFrame(this.#frame);
    this.#frame = 0;
  }

  set info(info) {
    this.#build();
    this.#info = info ?? null;
    this.#bounds = sceneBounds(Array.isArray(info?.scene_boxes) ? info.scene_boxes : []);
    this.#redraw();
  }

  set telemetry(message) {
    this.#telemetry = message;
    this.#redraw();
  }

  set localization(message) {
    this.#localization = message?.type === "localization" ? message : null;
    this.#redraw();
  }

  /** The occupancy grid answer, or null when there is no map yet. */
  set grid(grid) {
    this.#build();
    if (!grid) {
      this.#grid = null;
      this.#gridCanvas = null;
    } else if (grid !== this.#grid) {
      this.#gridCanvas = gridImage(grid); // may throw on a malformed map; the console shows a notice
      this.#grid = grid;
    }
    this.#redraw();
  }

  set goalFeedback(feedback) {
    this.#feedback = feedback ?? null;
    this.#redraw();
  }

  set target(target) {
    this.#target = Array.isArray(target) ? target : null;
    this.#redraw();
  }

  set note(text) {
    this.#build();
    this.#noteLine.textContent = text || "";
    this.#noteLine.hidden = !text;
  }

  #build() {
    if (this.#built) return;
    this.#built = true;
    this.classList.add("panel", "map");
    this.#canvas = h("canvas", {
      class: "map__canvas", width: 480, height: 360, tabindex: "0", role: "application",
      "data-wants-arrow-keys": "", "data-field": "map-canvas",
      "aria-label": "Lab map. Click or tap to set a go-to-goal target; with the keyboard, arrow keys move a cursor "
        + "and Enter sets the target.",
      "aria-describedby": "map-summary",
    });
    this.#canvas.addEventListener("click", (event) => this.#onClick(event));
    this.#canvas.addEventListener("keydown", (event) => this.#onKey(event));
    this.#canvas.addEventListener("focus", () => this.#redraw());
    this.#canvas.addEventListener("blur", () => this.#redraw());
    this.#summary = h("p", { class: "map__summary", id: "map-summary", "data-field": "map-summary", text: "Waiting for the robot…" });
    this.#cursorLine = h("p", { class: "map__cursor", "aria-live": "polite", "data-field": "map-cursor" });
    this.#noteLine = h("p", { class: "map__note muted", "data-field": "map-note", hidden: true });
    const key = (colour, text, shape = "line") => {
      const swatch = h("span", { class: `map__swatch map__swatch--${shape}`, "aria-hidden": "true" });
      swatch.style.setProperty("--swatch", colour); // CSSOM, not a style attribute: the CSP allows it
      return h("li", {}, swatch, text);
    };
    this.append(
      h("h2", { class: "panel__title", text: "Lab model" }),
      h("div", { class: "map__stage" }, this.#canvas),
      this.#summary,
      this.#cursorLine,
      this.#noteLine,
      h("ul", { class: "map__legend", "aria-label": "Map legend" },
        key(COLOURS.odometry, "odometry pose", "robot"), key(COLOURS.localized, "localized pose", "robot"),
        key(COLOURS.truth, "ground truth", "robot"), key(COLOURS.laser, "laser hits", "dot"),
        key("#c26a00", "sonar cones", "cone"), key(COLOURS.target, "target", "cross"),
        key("#444", "occupancy map", "cell")),
    );
  }

  #poses() {
    const odometry = this.#telemetry?.odometry?.pose;
    const loc = this.#localization;
    return {
      odometry: isPose(odometry) ? odometry : isPose(loc?.odometry) ? loc.odometry : null,
      localized: loc?.active && isPose(loc.estimate) ? loc.estimate : null,
      truth: isPose(loc?.ground_truth) ? loc.ground_truth : null,
    };
  }

  #redraw() {
    if (this.#frame || !this.#canvas) return;
    this.#frame = requestAnimationFrame(() => {
      this.#frame = 0;
      this.#draw();
    });
  }

  #draw() {
    const canvas = this.#canvas;
    const ratio = window.devicePixelRatio || 1;
    const cssWidth = canvas.clientWidth || 480;
    const width = Math.round(cssWidth * ratio);
    const height = Math.round(width * 0.72);
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

    if (this.#gridCanvas && this.#grid) {
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
    // Readings are drawn where the robot believes it is: the localized pose once localization runs.
    const sensorPose = poses.localized ?? poses.odometry;
    if (sensorPose) this.#drawSensors(ctx, sensorPose, px);
    for (const particle of (this.#localization?.particles ?? []).slice(0, 3000)) {
      if (!Array.isArray(particle)) continue;
      ctx.fillStyle = COLOURS.particle;
      ctx.fillRect(particle[0] - 1.5 * px, particle[1] - 1.5 * px, 3 * px, 3 * px);
    }
    const radius = Number(this.#info?.body_radius_m) || 0.2;
    if (poses.truth) this.#drawRobot(ctx, poses.truth, radius, COLOURS.truth, px, true);
    if (poses.localized) this.#drawRobot(ctx, poses.localized, radius, COLOURS.localized, px, true);
    if (poses.odometry) this.#drawRobot(ctx, poses.odometry, radius, COLOURS.odometry, px, false);

    const values = this.#feedback?.values ?? {};
    const goal = this.#target ?? (Number.isFinite(values.goal_x_m) && Number.isFinite(values.goal_y_m)
      ? [values.goal_x_m, values.goal_y_m] : null);
    if (goal) this.#cross(ctx, goal, COLOURS.target, 7 * px, 2.5 * px);
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
    this.#summarize(poses, goal);
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

  #drawSensors(ctx, pose, px) {
    const sonars = Array.isArray(this.#info?.sonars) ? this.#info.sonars : [];
    const ranges = this.#telemetry?.sonar?.ranges_m ?? [];
    ctx.fillStyle = COLOURS.sonar;
    sonars.forEach((sonar, index) => {
      const range = ranges[index];
      if (!isEcho(range, Number(sonar.max_range_m) || Infinity)) return;
      this.#polygon(ctx, sonarCone(pose, sonar, range));
      ctx.fill();
    });
    const laser = this.#telemetry?.laser;
    ctx.fillStyle = COLOURS.laser;
    for (const [x, y] of laserHits(pose, laser, Number(this.#info?.laser?.max_range_m) || Infinity)) {
      ctx.fillRect(x - 1.5 * px, y - 1.5 * px, 3 * px, 3 * px);
    }
  }

  #drawRobot(ctx, pose, radius, colour, px, outline) {
    ctx.lineWidth = 2.5 * px;
    ctx.strokeStyle = colour;
    ctx.fillStyle = outline ? "transparent" : `${colour}40`;
    ctx.beginPath();
    ctx.arc(pose.x_m, pose.y_m, radius, 0, 2 * Math.PI);
    if (!outline) ctx.fill();
    ctx.stroke();
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
    if (poses.odometry) parts.push(`Robot at (${fixed(poses.odometry.x_m)}, ${fixed(poses.odometry.y_m)}) m by odometry`);
    const loc = this.#localization;
    if (poses.localized) {
      parts.push(`localized at (${fixed(poses.localized.x_m)}, ${fixed(poses.localized.y_m)}) m`
        + `${loc.converged ? ", converged" : ", converging"}`
        + (Number.isFinite(loc.position_error_m) ? `, error ${fixed(loc.position_error_m, 3)} m` : "")
        + (Number.isFinite(loc.odometry_position_error_m) ? ` (odometry ${fixed(loc.odometry_position_error_m, 3)} m)` : ""));
    }
    if (goal) parts.push(`target (${fixed(goal[0])}, ${fixed(goal[1])}) m`);
    parts.push(this.#grid ? `map of ${this.#grid.scans_integrated ?? 0} scans` : "no map yet");
    const text = parts.length ? `${parts.join("; ")}.` : "Waiting for the robot…";
    if (this.#summary.textContent !== text) this.#summary.textContent = text;
  }

  #emitTarget(x_m, y_m) {
    this.#target = [x_m, y_m];
    this.#cursorLine.textContent = `Target set to (${fixed(x_m)}, ${fixed(y_m)}) m.`;
    this.dataset.targetX = fixed(x_m);
    this.dataset.targetY = fixed(y_m);
    this.dispatchEvent(new CustomEvent("map-target", { bubbles: true, detail: { x_m, y_m } }));
    this.#redraw();
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
      this.#cursorLine.textContent = `Cursor at (${fixed(this.#cursor[0])}, ${fixed(this.#cursor[1])}) m; Enter sets the target.`;
      this.#redraw();
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

export function register() {
  adoptStylesheet(new URL("./map-panel.css", import.meta.url));
  defineOnce("map-panel", MapPanel);
}
