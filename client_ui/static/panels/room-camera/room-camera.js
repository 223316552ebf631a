// <room-camera>: the robot seen from a pan-tilt-zoom camera mounted in the room (the 2003 lab's), drawn in the
// browser from the scene description (its room_cameras) and each telemetry message's camera_pose, where the robot
// truly stands, as a camera on the wall would show it (the middleware withholds that pose in graded runs: the panel
// then says so). Each viewer pans, tilts and zooms their own copy within the mount's limits: buttons, the arrow keys
// and + / - when it has focus, dragging, or the wheel; on a phone it is a fixed view. It draws only when something
// changed, at most 15 frames a second on a small screen.
// In: `scene` (GET /api/robots/<r>/scene), `telemetry` (its camera_pose).
// Out: data-camera (the camera's id), data-aim ("pan tilt hfov" in degrees), data-drawn-pose ("x y theta" drawn),
//      data-webgl ("ok" or "missing").

import * as THREE from "three";
import { h } from "../../lib/dom.js";
import { FrameCap, isSmallScreen } from "../../lib/frame-cap.js";
import { fixed, t } from "../../lib/i18n.js";
import { buildScene, placeRobot } from "../../lib/scene-three.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";

const PAN_STEP_RAD = THREE.MathUtils.degToRad(10);
const TILT_STEP_RAD = THREE.MathUtils.degToRad(5);
const ZOOM_STEP = 1.25;
const DRAG_RAD_PER_PX = 0.004;
const UP = new THREE.Vector3(0, 0, 1);

function isPose(pose) {
  return pose && [pose.x_m, pose.y_m, pose.theta_rad].every((v) => Number.isFinite(Number(v)));
}

const clamp = (value, low, high) => Math.min(high, Math.max(low, value));

export class RoomCameraPanel extends PanelElement {
  #canvas;
  #status;
  #controls;
  #renderer = null;
  #webgl = true;
  #three = null;
  #world = null;
  #camera = null;
  #mount = null;  // the scene's room camera
  #aim = null;    // {pan, tilt, hfov}: this viewer's
  #pose = null;
  #scene = null;
  #withheld = false;
  #frameCap = new FrameCap();
  #capTimer = 0;
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

  set scene(scene) {
    this.ensureBuilt();
    if (!scene || scene.version === this.#scene?.version) return;
    this.#scene = scene;
    this.#mount = scene.room_cameras?.[0] ?? null;
    this.dataset.camera = this.#mount?.id ?? "";
    if (!this.#mount) {
      this.#status.textContent = t("This robot's room has no camera.");
      this.#controls.hidden = true;
      return;
    }
    this.#aim = { pan: this.#mount.pan_rad, tilt: this.#mount.tilt_rad, hfov: this.#mount.hfov_deg };
    this.#controls.hidden = isSmallScreen();
    if (this.#webgl) this.#buildWorld();
    this.scheduleRender();
  }

  set telemetry(message) {
    const standing = message?.camera_pose;
    this.#withheld = message && !isPose(standing);
    if (isPose(standing)) this.#pose = standing;
    this.scheduleRender();
  }

  build() {
    this.classList.add("panel", "room-camera");
    this.#canvas = h("canvas", {
      class: "room-camera__canvas", "data-field": "room-camera-canvas", role: "img", tabindex: "0",
      "aria-label": t("The robot seen from the room's camera. Arrow keys pan and tilt, + and - zoom."),
    });
    this.#canvas.addEventListener("keydown", (event) => this.#key(event));
    this.#canvas.addEventListener("pointerdown", (event) => {
      if (isSmallScreen()) return;
      this.#drag = { x: event.clientX, y: event.clientY };
      this.#canvas.setPointerCapture?.(event.pointerId);
    });
    this.#canvas.addEventListener("pointermove", (event) => {
      if (!this.#drag) return;
      this.#turn((event.clientX - this.#drag.x) * DRAG_RAD_PER_PX, (event.clientY - this.#drag.y) * DRAG_RAD_PER_PX);
      this.#drag = { x: event.clientX, y: event.clientY };
    });
    for (const end of ["pointerup", "pointercancel", "lostpointercapture"]) {
      this.#canvas.addEventListener(end, () => { this.#drag = null; });
    }
    this.#canvas.addEventListener("wheel", (event) => {
      if (isSmallScreen()) return;
      event.preventDefault();
      this.#zoom(event.deltaY > 0 ? ZOOM_STEP : 1 / ZOOM_STEP);
    }, { passive: false });
    const button = (action, label, text, act) => h("button", { type: "button", class: "button button--secondary",
      "data-action": action, "aria-label": label, text, onclick: act });
    this.#controls = h("div", { class: "room-camera__controls", role: "group", "aria-label": t("Pan, tilt and zoom") },
      button("pan-left", t("Pan left"), "◀", () => this.#turn(PAN_STEP_RAD, 0)),
      button("pan-right", t("Pan right"), "▶", () => this.#turn(-PAN_STEP_RAD, 0)),
      button("tilt-up", t("Tilt up"), "▲", () => this.#turn(0, -TILT_STEP_RAD)),
      button("tilt-down", t("Tilt down"), "▼", () => this.#turn(0, TILT_STEP_RAD)),
      button("zoom-in", t("Zoom in"), "+", () => this.#zoom(1 / ZOOM_STEP)),
      button("zoom-out", t("Zoom out"), "−", () => this.#zoom(ZOOM_STEP)),
      button("reset-aim", t("Back to the camera's rest position"), t("Reset"), () => this.#reset()));
    this.#status = h("p", { class: "room-camera__status muted", "data-field": "room-camera-status", role: "status",
      text: t("Waiting for the lab's description…") });
    this.append(h("h2", { class: "panel__title", text: t("Room camera") }),
      h("div", { class: "room-camera__stage" }, this.#canvas), this.#controls, this.#status,
      this.messageLine({ class: "muted" }));
    try {
      this.#renderer = new THREE.WebGLRenderer({ canvas: this.#canvas, antialias: !isSmallScreen(),
        powerPreference: "low-power" });
      this.#renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, isSmallScreen() ? 1 : 2));
      this.dataset.webgl = "ok";
    } catch {
      this.#webgl = false;
      this.dataset.webgl = "missing";
      this.#canvas.hidden = true;
      this.#controls.hidden = true;
      this.#status.textContent = t("This browser cannot draw the room camera's view: WebGL is turned off or missing.");
    }
  }

  set note(text) {
    this.showMessage(text);
  }

  #buildWorld() {
    if (this.#world) {
      this.#three.remove(this.#world.lab, this.#world.robot);
      this.#world.dispose();
    }
    this.#three ??= new THREE.Scene();
    this.#camera ??= new THREE.PerspectiveCamera(45, 4 / 3, 0.05, 60);
    this.#world = buildScene(this.#scene);
    this.#three.add(this.#world.lab, this.#world.robot);
    this.#renderer.setClearColor(new THREE.Color(...this.#scene.camera.background_rgba.slice(0, 3)));
  }

  #key(event) {
    const moves = { ArrowLeft: [PAN_STEP_RAD, 0], ArrowRight: [-PAN_STEP_RAD, 0], ArrowUp: [0, -TILT_STEP_RAD],
      ArrowDown: [0, TILT_STEP_RAD] };
    if (moves[event.key]) this.#turn(...moves[event.key]);
    else if (event.key === "+" || event.key === "=") this.#zoom(1 / ZOOM_STEP);
    else if (event.key === "-") this.#zoom(ZOOM_STEP);
    else return;
    event.preventDefault();
  }

  #turn(panBy, tiltBy) {
    const mount = this.#mount;
    if (!mount || !this.#aim) return;
    this.#aim.pan = clamp(this.#aim.pan + panBy, mount.pan_rad - mount.pan_range_rad, mount.pan_rad + mount.pan_range_rad);
    this.#aim.tilt = clamp(this.#aim.tilt + tiltBy, ...mount.tilt_range_rad);
    this.scheduleRender();
  }

  #zoom(factor) {
    const mount = this.#mount;
    if (!mount || !this.#aim) return;
    this.#aim.hfov = clamp(this.#aim.hfov * factor, ...mount.hfov_range_deg);
    this.scheduleRender();
  }

  #reset() {
    const mount = this.#mount;
    if (!mount) return;
    this.#aim = { pan: mount.pan_rad, tilt: mount.tilt_rad, hfov: mount.hfov_deg };
    this.scheduleRender();
  }

  render() {
    if (!this.#webgl || !this.#world || !this.#mount) return;
    const width = this.#canvas.clientWidth;
    const height = this.#canvas.clientHeight;
    if (!width || !height) return;
    const size = this.#renderer.getSize(new THREE.Vector2());
    if (size.x !== width || size.y !== height) this.#renderer.setSize(width, height, false);
    const { pan, tilt, hfov } = this.#aim;
    const [x, y, z] = this.#mount.position_m;
    const aspect = width / height;
    this.#camera.aspect = aspect;
    this.#camera.fov = THREE.MathUtils.radToDeg(2 * Math.atan(Math.tan(THREE.MathUtils.degToRad(hfov) / 2) / aspect));
    this.#camera.updateProjectionMatrix();
    this.#camera.position.set(x, y, z);
    this.#camera.up.copy(UP);
    this.#camera.lookAt(x + Math.cos(pan) * Math.cos(tilt), y + Math.sin(pan) * Math.cos(tilt), z - Math.sin(tilt));
    const pose = this.#pose;
    this.#world.robot.visible = Boolean(pose);
    if (pose) placeRobot(this.#world.robot, pose);
    this.#frameCap.drawn(performance.now());
    this.#renderer.render(this.#three, this.#camera);
    const degrees = (rad) => fixed(THREE.MathUtils.radToDeg(rad), 1);
    this.dataset.aim = `${degrees(pan)} ${degrees(tilt)} ${fixed(hfov, 1)}`;
    this.dataset.drawnPose = pose ? `${fixed(pose.x_m, 3)} ${fixed(pose.y_m, 3)} ${fixed(pose.theta_rad, 3)}` : "";
    this.#status.textContent = this.#withheld
      ? t("The room camera is off during a graded run: it would show where the robot truly stands.")
      : pose ? t("{title}: pan {pan}°, tilt {tilt}°, field {hfov}°.",
        { title: t(this.#mount.title ?? ""), pan: degrees(pan), tilt: degrees(tilt), hfov: fixed(hfov, 0) })
        : t("Waiting for the robot's position…");
  }
}

export const register = registerPanel({
  kind: "room-camera", tag: "room-camera", element: RoomCameraPanel, span: 1,
  stylesheets: [new URL("./room-camera.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry" } },
    { service: "scene" },
  ],
});
