// <lab-view>: the lab in 3D, drawn in the browser from the robot's scene description and its pose stream (the
// "overview camera" the console lacked): the room with its walls, obstacles and floor markings in the colours the
// robot's camera sees, the robot at its odometry pose, its laser hits and sonar cones, and the goal. Orbit it by
// dragging (mouse: both ways; touch: sideways, so the page still scrolls), zoom with the wheel or the buttons, or
// look straight down. It draws only when something changed and it is on screen. Without WebGL it says so.
// In: `scene` (GET /api/robots/<r>/scene), `telemetry` (odometry pose, laser, sonar), `goalFeedback` (go-to-goal
//     feedback: its goal_x_m/goal_y_m), `target` ([x_m, y_m] picked on the map, or null), `note` (a sentence).
// Out: no events; what it drew is in data-drawn-pose ("x y theta" of the robot as drawn), data-scene-version,
//      data-laser-hits and data-webgl ("ok" or "missing"), for people's tools and tests.

import * as THREE from "three";
import { h } from "../../lib/dom.js";
import { isEcho } from "../../lib/polar.js";
import { buildScene, placeRobot } from "../../lib/scene-three.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";

const COLOURS = { laser: "#d1390f", sonar: "#c26a00", goal: "#b1261b" };
const SONAR_SEGMENTS = 6;
const FIELD_OF_VIEW_DEG = 45;
const ORBIT_START = { azimuth: -Math.PI / 2 - 0.5, elevation: 0.85 }; // from the south-south-west, looking down
const ELEVATION_LIMITS = [0.12, 1.45];
const ZOOM_STEP = 1.25;
const DRAG_RAD_PER_PX = 0.008;
const SMALL_SCREEN_PX = 600;
const FIT_NDC = 0.94; // the floor's farthest corner this far from the centre to the edge // below this width: no antialiasing and one device pixel per CSS pixel

function fixed(value, decimals = 2) {
  const number = Number(value);
  if (!Number.isFinite(number)) return "—";
  const text = number.toFixed(decimals);
  return Number(text) === 0 ? (0).toFixed(decimals) : text;
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

  /** A sentence about the view's data (the scene could not be loaded), or "" to clear it. */
  set note(text) {
    this.showMessage(text);
  }

  build() {
    this.classList.add("panel", "lab-view");
    this.#canvas = h("canvas", {
      class: "lab-view__canvas", "data-field": "lab-view-canvas", role: "img", "aria-describedby": "lab-view-summary",
      "aria-label": "The lab in 3D with the robot. Drag to turn the view; the buttons zoom and look from above.",
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
      text: "From above", onclick: () => this.#setAbove(!this.#view.above),
    });
    const zoomIn = h("button", { type: "button", class: "button button--secondary", "data-action": "zoom-in",
      "aria-label": "Zoom in", text: "+", onclick: () => this.#zoom(1 / ZOOM_STEP) });
    const zoomOut = h("button", { type: "button", class: "button button--secondary", "data-action": "zoom-out",
      "aria-label": "Zoom out", text: "−", onclick: () => this.#zoom(ZOOM_STEP) });
    this.#summary = h("p", { class: "lab-view__summary", id: "lab-view-summary", "data-field": "lab-view-summary",
      text: "Waiting for the lab's description…" });
    this.append(
      h("h2", { class: "panel__title", text: "3D lab view" }),
      h("div", { class: "lab-view__stage" }, this.#canvas),
      h("div", { class: "lab-view__actions" }, this.#aboveButton, zoomIn, zoomOut),
      this.#summary,
      this.messageLine({ class: "lab-view__note muted", "data-field": "lab-view-note" }),
    );
    this.#startRenderer();
  }

  #startRenderer() {
    const small = (window.innerWidth || 0) < SMALL_SCREEN_PX;
    try {
      this.#renderer = new THREE.WebGLRenderer({ canvas: this.#canvas, antialias: !small, powerPreference: "low-power" });
    } catch {
      this.#webgl = false;
      this.dataset.webgl = "missing";
      this.#canvas.hidden = true;
      this.#aboveButton.parentElement.hidden = true;
      this.#summary.replaceWith(h("p", { class: "lab-view__missing", role: "status", "data-field": "lab-view-webgl",
        text: "This browser cannot draw 3D here: WebGL is turned off or missing. The Lab model panel shows the same "
          + "lab from above in 2D, and the Camera panel the robot's own view." }));
      return;
    }
    this.dataset.webgl = "ok";
    this.#renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, small ? 1 : 2));
    this.#camera = new THREE.PerspectiveCamera(FIELD_OF_VIEW_DEG, 4 / 3, 0.05, 100);
    this.#three = new THREE.Scene();
    this.#laser = new THREE.Points(new THREE.BufferGeometry(),
      new THREE.PointsMaterial({ color: COLOURS.laser, size: small ? 3 : 4, sizeAttenuation: false }));
    this.#sonar = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({
      color: COLOURS.sonar, transparent: true, opacity: 0.22, depthWrite: false, side: THREE.DoubleSide }));
    this.#sonar.renderOrder = 10_000; // over the floor's paint
    this.#goal = goalMarker();
    for (const overlay of [this.#laser, this.#sonar, this.#goal]) {
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
    this.#aim(width / height);
    this.#renderer.render(this.#three, this.#camera);
    this.dataset.drawnPose = pose ? `${fixed(pose.x_m, 3)} ${fixed(pose.y_m, 3)} ${fixed(pose.theta_rad, 3)}` : "";
    this.dataset.laserHits = String(hits);
    this.#summarize(pose, hits, echoes, goal);
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
    this.#aboveButton.textContent = above ? "Orbit" : "From above";
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
      parts.push(`Robot at (${fixed(pose.x_m)}, ${fixed(pose.y_m)}) m facing ${heading}° by odometry`);
      parts.push(`${hits} laser hits`);
      if (echoes) parts.push(`${echoes} sonar echoes`);
    } else {
      parts.push(`The ${this.#scene.scene_name} lab; waiting for the robot's pose`);
    }
    if (goal) parts.push(`goal (${fixed(goal[0])}, ${fixed(goal[1])}) m`);
    const text = `${parts.join("; ")}.`;
    if (this.#summary.textContent !== text) this.#summary.textContent = text;
  }
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
  ],
});
