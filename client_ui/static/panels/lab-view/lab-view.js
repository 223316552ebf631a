// <lab-view>: the lab in 3D, drawn in the browser from the robot's scene description and its pose stream (the
// "overview camera" the console lacked): the room with its walls, obstacles and floor markings in the colours the
// robot's camera sees, the robot at its odometry pose, its laser hits and sonar cones, the goal and the path planned
// to it, and the occupancy map on the floor when the robot has one. Orbit it by dragging (mouse: both ways; touch:
// sideways, so the page still scrolls), zoom with the wheel or the buttons, or look straight down. It draws only when
// something changed and it is on screen, at most 15 frames a second on a small screen. Without WebGL it says so.
// In: `scene` (GET /api/robots/<r>/scene), `telemetry` (odometry pose, laser, sonar), `goalFeedback` (go-to-goal
//     feedback: its goal_x_m/goal_y_m and planned_path), `target` ([x_m, y_m] picked on the map, or null), `map` (the
//     occupancy grid of GET /api/robots/<r>/map, or null), `note` (a sentence).
// Out: no events; what it drew is in data-drawn-pose ("x y theta" of the robot as drawn), data-scene-version,
//      data-laser-hits, data-path-points (the planned path's points drawn), data-map-cells ("width height" of the
//      grid on the floor; absent without one) and data-webgl ("ok" or "missing"), for people's tools and tests.

import * as THREE from "three";
import { h } from "../../lib/dom.js";
import { FrameCap, isSmallScreen } from "../../lib/frame-cap.js";
import { isEcho } from "../../lib/polar.js";
import { buildScene, placeRobot } from "../../lib/scene-three.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed as localFixed, t } from "../../lib/i18n.js";

const COLOURS = { laser: "#d1390f", sonar: "#c26a00", goal: "#b1261b", path: "#b1261b" };
const SONAR_SEGMENTS = 6;
const FIELD_OF_VIEW_DEG = 45;
const ORBIT_START = { azimuth: -Math.PI / 2 - 0.5, elevation: 0.85 }; // from the south-south-west, looking down
const ELEVATION_LIMITS = [0.12, 1.45];
const ZOOM_STEP = 1.25;
const DRAG_RAD_PER_PX = 0.008;
const FIT_NDC = 0.94; // the floor's farthest corner this far from the centre to the edge
const PATH_POINTS = 65; // the robot's believed pose and the 64 waypoints goal feedback carries at most
const PATH_WIDTH_M = 0.06;
const PATH_HEIGHT_M = 0.02; // above the floor's paint and the map
const MAP_LIFT_M = 0.004; // the map lies this far above the floor's highest paint
const UNKNOWN_CELL = 255;

function fixed(value, decimals = 2) {
  const number = Number(value);
  if (!Number.isFinite(number)) return "—";
  const text = number.toFixed(decimals); // data, not text: data attributes; said() writes it for people
  return Number(text) === 0 ? (0).toFixed(decimals) : text; // data, not text: no "-0.00"
}

// A number a person reads: as fixed() rounds it, with the page's language's decimal sign ("0,25" in Spanish).
function said(value, decimals = 2) {
  const text = fixed(value, decimals);
  return text === "—" ? text : localFixed(Number(text), decimals);
}

function isPose(pose) {
  return pose && [pose.x_m, pose.y_m, pose.theta_rad].every((v) => Number.isFinite(Number(v)));
}

export class LabView extends PanelElement {
  #canvas;
  #summary;
  #aboveButton;
  #renderer = null;
  #webgl = true;
  #world = null;        // {lab, robot, bounds, dispose} of the scene drawn
  #three = null;        // the three.js scene: world, overlays, camera
  #camera = null;
  #laser = null;        // Points
  #sonar = null;        // Mesh of fans
  #goal = null;         // Group
  #path = null;         // Mesh: a ribbon on the floor through the planned path
  #pathPoints = 0;
  #pathWaypoints = 0;
  #pathDrawn = [];
  #paintTopM = 0;       // the floor's highest paint: the map lies just above it
  #map = null;          // {grid, mesh} of the occupancy grid drawn on the floor
  #grid = null;
  #frameCap = new FrameCap();
  #capTimer = 0;
  #scene = null;
  #pose = null;
  #telemetry = null;
  #feedback = null;
  #target = null;
  #view = { above: false, azimuth: ORBIT_START.azimuth, elevation: ORBIT_START.elevation, zoom: 1 };
  #drag = null;
  #resizeObserver = null;

  connectedCallback() {
    super.connectedCallback();
    this.#resizeObserver ??= new ResizeObserver(() => this.scheduleRender());
    this.#resizeObserver.observe(this.#canvas);
  }

  disconnectedCallback() {
    super.disconnectedCallback();
    this.#resizeObserver?.disconnect();
    clearTimeout(this.#capTimer);
    this.#capTimer = 0;
  }

  /** Draws on the next animation frame, but on a small screen no sooner than the frame cap allows; whatever came
   *  meanwhile is drawn then (the newest pose wins). */
  scheduleRender() {
    if (this.#capTimer) return;
    const waitMs = this.#frameCap.waitMs(performance.now());
    if (waitMs <= 0) {
      super.scheduleRender();
      return;
    }
    this.#capTimer = setTimeout(() => {
      this.#capTimer = 0;
      super.scheduleRender();
    }, waitMs);
  }

  /** The scene description: the lab is (re)built when its version changes. */
  set scene(scene) {
    this.ensureBuilt();
    if (!scene || scene.version === this.#scene?.version) return;
    this.#scene = scene;
    this.dataset.sceneVersion = scene.version;
    if (this.#webgl) this.#buildWorld();
    this.scheduleRender();
  }

  set telemetry(message) {
    this.#telemetry = message;
    const pose = message?.odometry?.pose;
    if (isPose(pose)) this.#pose = pose;
    this.scheduleRender();
  }

  set goalFeedback(feedback) {
    this.#feedback = feedback ?? null;
    this.scheduleRender();
  }

  set target(target) {
    this.#target = Array.isArray(target) ? target : null;
    this.scheduleRender();
  }

  /** The occupancy grid (the map answer's `map`), or null when the robot has none: drawn on the floor. */
  set map(grid) {
    this.ensureBuilt();
    this.#grid = grid ?? null;
    if (this.#webgl && this.#three) this.#placeMap();
    this.scheduleRender();
  }

  /** A sentence about the view's data (the scene could not be loaded), or "" to clear it. */
  set note(text) {
    this.showMessage(text);
  }

  build() {
    this.classList.add("panel", "lab-view");
    this.#canvas = h("canvas", {
      class: "lab-view__canvas", "data-field": "lab-view-canvas", role: "img", "aria-describedby": "lab-view-summary",
      "aria-label": t("The lab in 3D with the robot. Drag to turn the view; the buttons zoom and look from above."),
    });
    this.#canvas.addEventListener("pointerdown", (event) => this.#startDrag(event));
    this.#canvas.addEventListener("pointermove", (event) => this.#moveDrag(event));
    for (const end of ["pointerup", "pointercancel", "lostpointercapture"]) {
      this.#canvas.addEventListener(end, () => { this.#drag = null; });
    }
    this.#canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      this.#zoom(event.deltaY > 0 ? ZOOM_STEP : 1 / ZOOM_STEP);
    }, { passive: false });
    this.#aboveButton = h("button", {
      type: "button", class: "button button--secondary", "data-action": "view-above", "aria-pressed": "false",
      text: t("From above"), onclick: () => this.#setAbove(!this.#view.above),
    });
    const zoomIn = h("button", { type: "button", class: "button button--secondary", "data-action": "zoom-in",
      "aria-label": t("Zoom in"), text: "+", onclick: () => this.#zoom(1 / ZOOM_STEP) });
    const zoomOut = h("button", { type: "button", class: "button button--secondary", "data-action": "zoom-out",
      "aria-label": t("Zoom out"), text: "−", onclick: () => this.#zoom(ZOOM_STEP) });
    this.#summary = h("p", { class: "lab-view__summary", id: "lab-view-summary", "data-field": "lab-view-summary",
      text: t("Waiting for the lab's description…") });
    this.append(
      h("h2", { class: "panel__title", text: t("3D lab view") }),
      h("div", { class: "lab-view__stage" }, this.#canvas),
      h("div", { class: "lab-view__actions" }, this.#aboveButton, zoomIn, zoomOut),
      this.#summary,
      this.messageLine({ class: "lab-view__note muted", "data-field": "lab-view-note" }),
    );
    this.#startRenderer();
  }

  #startRenderer() {
    const small = isSmallScreen();
    try {
      this.#renderer = new THREE.WebGLRenderer({ canvas: this.#canvas, antialias: !small, powerPreference: "low-power" });
    } catch {
      this.#webgl = false;
      this.dataset.webgl = "missing";
      this.#canvas.hidden = true;
      this.#aboveButton.parentElement.hidden = true;
      this.#summary.replaceWith(h("p", { class: "lab-view__missing", role: "status", "data-field": "lab-view-webgl",
        text: t("This browser cannot draw 3D here: WebGL is turned off or missing. The Lab model panel shows the same lab from above in 2D, and the Camera panel the robot's own view.") }));
      return;
    }
    this.dataset.webgl = "ok";
    this.#renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, small ? 1 : 2)); // fewer pixels on a phone
    this.#camera = new THREE.PerspectiveCamera(FIELD_OF_VIEW_DEG, 4 / 3, 0.05, 100);
    this.#three = new THREE.Scene();
    this.#laser = new THREE.Points(new THREE.BufferGeometry(),
      new THREE.PointsMaterial({ color: COLOURS.laser, size: small ? 3 : 4, sizeAttenuation: false }));
    this.#sonar = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({
      color: COLOURS.sonar, transparent: true, opacity: 0.22, depthWrite: false, side: THREE.DoubleSide }));
    this.#sonar.renderOrder = 10_000; // over the floor's paint
    this.#goal = goalMarker();
    this.#path = pathRibbon();
    for (const overlay of [this.#laser, this.#sonar, this.#goal, this.#path]) {
      overlay.frustumCulled = false;
      this.#three.add(overlay);
    }
  }

  #buildWorld() {
    const scene = this.#scene;
    if (this.#world) {
      this.#three.remove(this.#world.lab, this.#world.robot);
      this.#world.dispose();
    }
    this.#world = buildScene(scene);
    this.#three.add(this.#world.lab, this.#world.robot);
    this.#paintTopM = Math.max(0, Number(scene.floor?.top_z_m) || 0,
      ...(scene.marks ?? []).map((mark) => Number(mark.top_z_m) || 0));
    if (this.#map) this.#map.mesh.position.z = this.#paintTopM + MAP_LIFT_M;
    this.#renderer.setClearColor(new THREE.Color(...scene.camera.background_rgba.slice(0, 3)));
    const beams = Number(scene.laser?.beam_count) || 0;
    this.#laser.geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(beams * 3), 3));
    const sonars = scene.sonar?.sonars?.length ?? 0;
    this.#sonar.geometry.setAttribute("position",
      new THREE.BufferAttribute(new Float32Array(sonars * SONAR_SEGMENTS * 9), 3));
  }

  render() {
    if (!this.#webgl || !this.#world) return;
    const canvas = this.#canvas;
    const width = canvas.clientWidth;
    const height = canvas.clientHeight;
    if (!width || !height) return; // on another tab: drawn when shown (the ResizeObserver asks again)
    const size = this.#renderer.getSize(new THREE.Vector2());
    if (size.x !== width || size.y !== height) this.#renderer.setSize(width, height, false);
    const pose = this.#pose;
    this.#world.robot.visible = Boolean(pose);
    if (pose) placeRobot(this.#world.robot, pose);
    const hits = pose ? this.#placeLaser(pose) : 0;
    const echoes = pose ? this.#placeSonar(pose) : 0;
    const goal = this.#goalPoint();
    this.#goal.visible = Boolean(goal);
    if (goal) this.#goal.position.set(goal[0], goal[1], 0);
    this.#placePath();
    this.#aim(width / height);
    this.#frameCap.drawn(performance.now());
    this.#renderer.render(this.#three, this.#camera);
    this.dataset.drawnPose = pose ? `${fixed(pose.x_m, 3)} ${fixed(pose.y_m, 3)} ${fixed(pose.theta_rad, 3)}` : "";
    this.dataset.laserHits = String(hits);
    this.dataset.pathPoints = String(this.#pathPoints);
    this.#summarize(pose, hits, echoes, goal);
  }

  /** The go-to-goal path still ahead, from the pose the skill steers by through its waypoints, as a flat ribbon. */
  #placePath() {
    const feedback = this.#feedback;
    const waypoints = Array.isArray(feedback?.planned_path) ? feedback.planned_path : [];
    const start = isPose(feedback?.pose) ? [[Number(feedback.pose.x_m), Number(feedback.pose.y_m)]] : [];
    const points = [...start, ...waypoints].filter((point) => Array.isArray(point)
      && Number.isFinite(Number(point[0])) && Number.isFinite(Number(point[1]))).slice(0, PATH_POINTS);
    this.#pathPoints = waypoints.length && points.length >= 2 ? points.length : 0;
    this.#pathWaypoints = this.#pathPoints ? points.length - start.length : 0;
    this.#pathDrawn = this.#pathPoints ? points.map((point) => point.map(Number)) : [];
    const attribute = this.#path.geometry.getAttribute("position");
    let vertices = 0;
    for (let i = 1; i < this.#pathPoints; i += 1) {
      const [x0, y0] = points[i - 1].map(Number);
      const [x1, y1] = points[i].map(Number);
      const length = Math.hypot(x1 - x0, y1 - y0);
      if (length < 1e-6) continue;
      const nx = (-(y1 - y0) / length) * (PATH_WIDTH_M / 2);
      const ny = ((x1 - x0) / length) * (PATH_WIDTH_M / 2);
      const corners = [[x0 + nx, y0 + ny], [x0 - nx, y0 - ny], [x1 + nx, y1 + ny], [x1 - nx, y1 - ny]];
      for (const index of [0, 1, 2, 2, 1, 3]) {
        attribute.setXYZ(vertices, corners[index][0], corners[index][1], PATH_HEIGHT_M);
        vertices += 1;
      }
    }
    attribute.needsUpdate = true;
    this.#path.geometry.setDrawRange(0, vertices);
    this.#path.visible = vertices > 0;
  }

  /** The occupancy grid as a texture on the floor: free cells light, occupied ones dark, unknown ones not drawn. */
  #placeMap() {
    const grid = this.#grid;
    if (this.#map && this.#map.grid === grid) return;
    if (this.#map) {
      this.#three.remove(this.#map.mesh);
      this.#map.mesh.geometry.dispose();
      this.#map.mesh.material.map.dispose();
      this.#map.mesh.material.dispose();
      this.#map = null;
    }
    delete this.dataset.mapCells;
    const texture = grid ? gridTexture(grid) : null;
    if (!texture) return;
    const resolution = Number(grid.resolution_m);
    const width = grid.width_cells * resolution;
    const height = grid.height_cells * resolution;
    const mesh = new THREE.Mesh(new THREE.PlaneGeometry(width, height), new THREE.MeshBasicMaterial({
      map: texture, transparent: true, depthWrite: false }));
    mesh.position.set(Number(grid.origin_x_m) + width / 2, Number(grid.origin_y_m) + height / 2,
      this.#paintTopM + MAP_LIFT_M);
    mesh.renderOrder = 9_000; // over the floor's paint, under the sonar cones
    this.#three.add(mesh);
    this.#map = { grid, mesh };
    this.dataset.mapCells = `${grid.width_cells} ${grid.height_cells}`;
  }

  #goalPoint() {
    const values = this.#feedback?.values ?? {};
    if (this.#target) return this.#target;
    return Number.isFinite(values.goal_x_m) && Number.isFinite(values.goal_y_m) ? [values.goal_x_m, values.goal_y_m] : null;
  }

  /** Laser hits at the scan's height, placed by the odometry pose; returns how many. */
  #placeLaser(pose) {
    const laser = this.#telemetry?.laser;
    const attribute = this.#laser.geometry.getAttribute("position");
    const ranges = Array.isArray(laser?.ranges_m) ? laser.ranges_m : [];
    const maxRange = Number(this.#scene.laser?.max_range_m) || Infinity;
    const heightM = Number(this.#scene.laser?.height_m) || 0.2;
    let count = 0;
    ranges.slice(0, attribute.count).forEach((range, index) => {
      if (!isEcho(range, maxRange)) return;
      const angle = pose.theta_rad + Number(laser.angle_min_rad) + index * Number(laser.angle_increment_rad);
      attribute.setXYZ(count, pose.x_m + range * Math.cos(angle), pose.y_m + range * Math.sin(angle), heightM);
      count += 1;
    });
    attribute.needsUpdate = true;
    this.#laser.geometry.setDrawRange(0, count);
    return count;
  }

  /** One flat fan per echoing sonar, from the rim out to its range; returns how many echo. */
  #placeSonar(pose) {
    const ring = this.#scene.sonar;
    const ranges = this.#telemetry?.sonar?.ranges_m ?? [];
    const attribute = this.#sonar.geometry.getAttribute("position");
    const positions = attribute.array;
    positions.fill(0);
    let echoes = 0;
    (ring?.sonars ?? []).forEach((sonar, index) => {
      const range = ranges[index];
      if (!isEcho(range, Number(sonar.max_range_m) || Infinity)) return;
      echoes += 1;
      const axis = pose.theta_rad + sonar.mount_angle_rad;
      const ox = pose.x_m + ring.mount_radius_m * Math.cos(axis);
      const oy = pose.y_m + ring.mount_radius_m * Math.sin(axis);
      for (let s = 0; s < SONAR_SEGMENTS; s += 1) {
        const a0 = axis - sonar.cone_half_angle_rad + (2 * sonar.cone_half_angle_rad * s) / SONAR_SEGMENTS;
        const a1 = a0 + (2 * sonar.cone_half_angle_rad) / SONAR_SEGMENTS;
        positions.set([ox, oy, ring.height_m, ox + range * Math.cos(a0), oy + range * Math.sin(a0), ring.height_m,
          ox + range * Math.cos(a1), oy + range * Math.sin(a1), ring.height_m], (index * SONAR_SEGMENTS + s) * 9);
      }
    });
    attribute.needsUpdate = true;
    return echoes;
  }

  /** Places the overview camera: orbiting the room's centre, or straight above it with north up; either way far
   *  enough for the floor and the tallest wall's top to fit (times the zoom). */
  #aim(aspect) {
    const b = this.#world.bounds;
    const centre = new THREE.Vector3((b.minX + b.maxX) / 2, (b.minY + b.maxY) / 2, 0);
    const corners = [];
    for (const x of [b.minX, b.maxX]) {
      for (const y of [b.minY, b.maxY]) corners.push(new THREE.Vector3(x, y, 0), new THREE.Vector3(x, y, b.maxZ));
    }
    const camera = this.#camera;
    camera.aspect = aspect;
    let distance = Math.hypot(b.maxX - b.minX, b.maxY - b.minY);
    // Perspective is not linear in the distance: a few rounds of "move back by how far the worst corner is out".
    for (let round = 0; round < 4; round += 1) {
      this.#place(camera, centre, distance);
      const worst = Math.max(...corners.map((corner) => {
        const ndc = corner.clone().project(camera);
        return Math.max(Math.abs(ndc.x), Math.abs(ndc.y));
      }));
      distance *= worst / FIT_NDC;
    }
    this.#place(camera, centre, distance * this.#view.zoom);
  }

  #place(camera, centre, distance) {
    if (this.#view.above) {
      camera.up.set(0, 1, 0);
      camera.position.set(centre.x, centre.y, distance);
    } else {
      const { azimuth, elevation } = this.#view;
      camera.up.set(0, 0, 1);
      camera.position.set(centre.x + distance * Math.cos(elevation) * Math.cos(azimuth),
        centre.y + distance * Math.cos(elevation) * Math.sin(azimuth), distance * Math.sin(elevation));
    }
    camera.far = distance * 4;
    camera.lookAt(centre);
    camera.updateProjectionMatrix();
    camera.updateMatrixWorld();
  }

  #setAbove(above) {
    this.#view.above = above;
    this.#aboveButton.setAttribute("aria-pressed", String(above));
    this.#aboveButton.textContent = above ? t("Orbit") : t("From above");
    this.dataset.view = above ? "above" : "orbit";
    this.scheduleRender();
  }

  #zoom(factor) {
    this.#view.zoom = Math.min(3, Math.max(0.25, this.#view.zoom * factor));
    this.scheduleRender();
  }

  #startDrag(event) {
    if (!this.#webgl) return;
    this.#drag = { x: event.clientX, y: event.clientY, touch: event.pointerType === "touch" };
    this.#canvas.setPointerCapture?.(event.pointerId);
  }

  #moveDrag(event) {
    if (!this.#drag) return;
    const dx = event.clientX - this.#drag.x;
    const dy = event.clientY - this.#drag.y;
    this.#drag.x = event.clientX;
    this.#drag.y = event.clientY;
    if (this.#view.above) this.#setAbove(false);
    this.#view.azimuth -= dx * DRAG_RAD_PER_PX;
    if (!this.#drag.touch) {
      const [low, high] = ELEVATION_LIMITS;
      this.#view.elevation = Math.min(high, Math.max(low, this.#view.elevation + dy * DRAG_RAD_PER_PX));
    }
    this.scheduleRender();
  }

  /** The planned path's points as last drawn, [[x_m, y_m], ...] from the skill's pose on (for tools and tests). */
  get plannedPath() {
    return this.#pathDrawn.map((point) => [...point]);
  }

  /** Draws now and reads back the colour drawn where a world point lands: {css: [x, y], rgba: [0..255 x4]} or
   *  null when it is off the canvas or nothing is drawn yet (for tools and tests). */
  drawnColourAt(x_m, y_m, z_m) {
    if (!this.#webgl || !this.#world) return null;
    this.render();
    const projected = new THREE.Vector3(x_m, y_m, z_m).project(this.#camera);
    const buffer = this.#renderer.getDrawingBufferSize(new THREE.Vector2());
    const px = Math.round(((projected.x + 1) / 2) * buffer.x);
    const py = Math.round(((projected.y + 1) / 2) * buffer.y); // from the bottom, as GL reads
    if (px < 0 || py < 0 || px >= buffer.x || py >= buffer.y) return null;
    const gl = this.#renderer.getContext();
    const rgba = new Uint8Array(4);
    gl.readPixels(px, py, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, rgba); // same task as the draw: the buffer still holds it
    const ratio = buffer.x / this.#canvas.clientWidth;
    return { css: [px / ratio, (buffer.y - py) / ratio], rgba: Array.from(rgba) };
  }

  #summarize(pose, hits, echoes, goal) {
    const parts = [];
    if (pose) {
      const heading = Math.round((pose.theta_rad * 180) / Math.PI);
      parts.push(t("Robot at ({x_m}, {y_m}) m facing {heading}° by odometry", { x_m: said(pose.x_m), y_m: said(pose.y_m), heading }));
      parts.push(t("{hits} laser hits", { hits }));
      if (echoes) parts.push(t("{echoes} sonar echoes", { echoes }));
    } else {
      parts.push(t("The {value} lab; waiting for the robot's pose", { value: this.#scene.scene_name }));
    }
    if (goal) parts.push(t("goal ({value}, {value2}) m", { value: said(goal[0]), value2: said(goal[1]) }));
    if (this.#pathWaypoints) parts.push(t("planned path of {value} waypoints", { value: this.#pathWaypoints }));
    if (this.#map) parts.push(t("map of {value} scans on the floor", { value: this.#grid.scans_integrated ?? 0 }));
    const text = `${parts.join("; ")}.`;
    if (this.#summary.textContent !== text) this.#summary.textContent = text;
  }
}

/** A flat ribbon through up to PATH_POINTS points (two triangles a segment), placed by #placePath. */
function pathRibbon() {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array((PATH_POINTS - 1) * 6 * 3), 3));
  const ribbon = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: COLOURS.path, side: THREE.DoubleSide }));
  ribbon.visible = false;
  return ribbon;
}

/** The occupancy grid as an RGBA texture, one texel a cell, row 0 the lowest y (as the plane's v); null when its
 *  size and its cells disagree. Cells hold 0-100 (% occupied) or UNKNOWN_CELL. */
function gridTexture(grid) {
  const width = Number(grid.width_cells);
  const height = Number(grid.height_cells);
  if (!(Number.isInteger(width) && Number.isInteger(height) && width > 0 && height > 0)
    || !(Number(grid.resolution_m) > 0)) return null;
  let bytes;
  try {
    bytes = Uint8Array.from(atob(String(grid.cells_b64)), (c) => c.charCodeAt(0));
  } catch {
    return null;
  }
  if (bytes.length < width * height) return null;
  const rgba = new Uint8Array(width * height * 4);
  for (let i = 0; i < width * height; i += 1) {
    const value = bytes[i];
    if (value === UNKNOWN_CELL) continue; // transparent: the floor shows through
    const free = value < 50;
    const shade = free ? 255 : Math.round(150 - ((Math.min(100, value) - 50) / 50) * 130);
    rgba.set([shade, shade, free ? 255 : shade, free ? 110 : 235], i * 4);
  }
  const texture = new THREE.DataTexture(rgba, width, height, THREE.RGBAFormat);
  texture.magFilter = THREE.NearestFilter;
  texture.minFilter = THREE.NearestFilter;
  texture.colorSpace = THREE.SRGBColorSpace;
  texture.needsUpdate = true;
  return texture;
}

/** A red pin standing on the goal. */
function goalMarker() {
  const material = new THREE.MeshBasicMaterial({ color: COLOURS.goal });
  const pole = new THREE.Mesh(new THREE.CylinderGeometry(0.015, 0.015, 0.5, 8).rotateX(Math.PI / 2), material);
  pole.position.z = 0.25;
  const head = new THREE.Mesh(new THREE.SphereGeometry(0.07, 16, 12), material);
  head.position.z = 0.52;
  const ring = new THREE.Mesh(new THREE.RingGeometry(0.12, 0.16, 32), material);
  ring.position.z = 0.01;
  const marker = new THREE.Group();
  marker.add(pole, head, ring);
  marker.visible = false;
  return marker;
}

export const register = registerPanel({
  kind: "lab-view", tag: "lab-view", element: LabView, span: 2,
  stylesheets: [new URL("./lab-view.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry" } },
    { service: "scene" },
    { service: "goal-view" },
    { service: "map-view" },
  ],
});
