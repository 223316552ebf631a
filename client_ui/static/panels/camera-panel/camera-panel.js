// <camera-panel>: draws the robot's camera stream, or the view this browser draws from the robot's pose, on a canvas
// and shows the frame rate and the picture's age; its words say which of the two the picture is.
// In: `robotName` (string), `frame` (ArrayBuffer from the camera socket), `message` (status/error
// JSON from the server; the error `obstacles_hidden` puts its sentence in place of the picture), `connected` (bool: is the camera socket open), and for the feedback layer
// `info` (RobotInfo: camera size and field of view), `driveReady` / `driveSent` (the drive socket's
// "ready" and every message sent on it), `feedbackEnabled` (bool), `feedbackFill` ("edges" | "black": what
// fills the view the frame does not cover), `telemetry` (its laser scan sets the depth the zoom assumes; while the
// picture is drawn here, its `camera_pose`, where the robot truly stands, is where the view is drawn from; null in
// a graded run, when the panel turns to the video), `scene` (the robot's scene
// description: offers the picture drawn by this browser), `source` ("video" | "drawn").
// Out: `camera-feedback-change` {enabled} when the person turns the motion preview on or off,
// `camera-feedback-fill-change` {fill} when they choose the fill, `camera-injected-delay-change` {delay_s} when an
// added delay begins, changes or ends, `camera-source-change` {source} when they
// choose where the picture comes from (the wiring closes the video socket while it is drawn here; `fallback` is true
// when this browser cannot draw it and the video comes back without the person choosing it), and, not bubbling,
// `camera-frame-shown` {source, capture_unix_s, shown_unix_s} each time a frame is put on the canvas (for tools: the
// browser-view benchmark's capture-to-glass delay). On a small screen the drawn picture is drawn at most 15 times a
// second, from the newest pose.

import { h } from "../../lib/dom.js";
import { framesInWindow, parseFramePacket } from "../../lib/camera-frame.js";
import { FrameCap, isSmallScreen } from "../../lib/frame-cap.js";
import { FILL_MODES, FeedbackLayer } from "./camera-feedback.js";
import { DrawnView } from "./drawn-view.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed, number, t } from "../../lib/i18n.js";

const FPS_WINDOW_MS = 1000;
const SOURCES = ["video", "drawn"];
const TRUTH_WITHHELD = t("During your graded run the picture is the robot's own camera video: a picture drawn here would need where the robot truly stands, which stays on the server until the run ends.");
const WITHHELD_CODE = "obstacles_hidden"; // the camera's refusal during the viewer's obstacle-zone test
// What the panel calls its picture, by source: a drawn picture is neither video nor live.
const WORDS = {
  video: { age: t("video age "), delay: t("video delay "), waiting: t("Waiting for video…") },
  drawn: { age: t("picture age "), delay: t("picture delay "), waiting: t("Waiting for the robot's pose to draw its view…") },
};

export class CameraPanel extends PanelElement {
  #canvas;
  #placeholder;
  #fpsOutput;
  #ageOutput;
  #sequenceOutput;
  #messageLine;
  #decoding = false;
  #pending = null;
  #drawTimesMs = [];
  #robotName = "";
  #statsTimer = 0;
  #lastHeader = null;
  #stage;
  #feedback = new FeedbackLayer();
  #bitmap = null;
  #feedbackToggle;
  #feedbackLock;
  #fillSelect;
  #delayOutput;
  #injectedBadge;
  #sourceSelect;
  #source = "video";
  #scene = null;
  #drawn = null;          // DrawnView, once made
  #drawnProblem = "";
  #videoNote = "";        // why the video shows though the person chose the drawn picture (a graded run)
  #videoNoteIsProblem = false; // this browser cannot draw (no WebGL): shown as a problem, which a phone keeps in view
  #drawing = false;       // a drawn frame is being made
  #nextPose = null;       // the newest telemetry not drawn yet: it replaces any older one waiting
  #withheld = false;      // the server refused the video (an obstacle-zone test): its sentence stays
  #poseTimer = 0;
  #frameCap = new FrameCap();
  #ageLabel;
  #delayLabel;

  connectedCallback() {
    super.connectedCallback();
    clearInterval(this.#statsTimer);
    // Frame rate must fall to 0 when frames stop, so it is refreshed on a clock, not per frame.
    this.#statsTimer = setInterval(() => this.#showStats(), 250);
  }

  disconnectedCallback() {
    super.disconnectedCallback();
    clearInterval(this.#statsTimer);
    clearTimeout(this.#poseTimer);
    this.#poseTimer = 0;
  }

  build() {
    this.classList.add("panel");
    this.#canvas = h("canvas", { class: "camera__canvas", width: 320, height: 240, role: "img", id: "camera-canvas" });
    this.#placeholder = h("p", { class: "camera__placeholder", "data-field": "camera-placeholder",
      text: WORDS.video.waiting });
    this.#fpsOutput = h("span", { "data-field": "fps", text: "0" });
    this.#ageOutput = h("span", { "data-field": "video-age", text: "—" });
    this.#ageLabel = h("span", { "data-field": "age-label", text: WORDS.video.age });
    this.#delayLabel = h("span", { "data-field": "delay-label", text: WORDS.video.delay });
    this.#sequenceOutput = h("span", { "data-field": "frame-sequence", text: "—" });
    this.#messageLine = this.messageLine({ class: "camera__message", "data-field": "camera-message" });
    this.#delayOutput = h("span", { "data-field": "video-delay", text: "—" });
    this.#injectedBadge = h("span", { class: "camera__injected", "data-field": "injected-delay", hidden: true });
    this.#feedbackToggle = h("input", { type: "checkbox", id: "camera-feedback-toggle", "data-field": "feedback-toggle" });
    this.#feedbackToggle.checked = this.#feedback.enabled;
    this.#feedbackToggle.addEventListener("change", () => {
      this.feedbackEnabled = this.#feedbackToggle.checked;
      this.emit("camera-feedback-change", { enabled: this.#feedbackToggle.checked });
    });
    this.#feedbackLock = h("span", { class: "camera__lock", id: "camera-feedback-lock", "data-field": "feedback-lock",
      hidden: true });
    this.#fillSelect = h("select", { id: "camera-feedback-fill", "data-field": "feedback-fill" },
      h("option", { value: "edges", text: t("continue the picture") }),
      h("option", { value: "black", text: "black" }));
    this.#fillSelect.value = this.#feedback.fill;
    this.#sourceSelect = h("select", { id: "camera-source", "data-field": "camera-source" },
      h("option", { value: "video", text: t("the robot's camera (video)") }),
      h("option", { value: "drawn", text: t("drawn by this browser from the robot's pose"), disabled: true }));
    this.#sourceSelect.addEventListener("change", () => {
      this.source = this.#sourceSelect.value;
      this.emit("camera-source-change", { source: this.#source });
    });
    this.#fillSelect.addEventListener("change", () => {
      this.feedbackFill = this.#fillSelect.value;
      this.emit("camera-feedback-fill-change", { fill: this.#feedback.fill });
    });
    this.append(
      h("h2", { class: "panel__title", id: "camera-title", text: t("Camera") }),
      this.#stage = h("div", { class: "camera__stage" }, this.#canvas, this.#placeholder),
      h("p", { class: "camera__stats" },
        h("span", {}, this.#fpsOutput, t(" fps")),
        h("span", {}, this.#ageLabel, this.#ageOutput, t(" ms")),
        h("span", { hidden: true }, t("frame "), this.#sequenceOutput), // a number for tests and tools, not people
        h("span", { title: t("From sending a command to the first frame that shows it") },
          this.#delayLabel, this.#delayOutput, " s"),
        this.#injectedBadge),
      // Folded on a phone, where the picture and the drive pad must share one screen.
      h("details", { class: "camera__options", open: window.matchMedia("(min-width: 760px)").matches },
        h("summary", { text: t("Picture and motion preview") }),
        h("p", { class: "camera__feedback" },
          h("label", { class: "camera__source" }, t("Picture: "), this.#sourceSelect)),
        h("p", { class: "camera__feedback" },
          h("label", {}, this.#feedbackToggle, t(" Move the picture at once with my commands")),
          h("label", { class: "camera__fill" }, t("Where the frame shows nothing: "), this.#fillSelect),
          this.#feedbackLock)),
      this.#messageLine,
    );
    this.#applyLabel();
  }

  set robotName(name) {
    this.#robotName = String(name);
    this.#applyLabel();
  }

  /** While the socket is down the last frame stays, dimmed, so nobody mistakes it for live video. */
  set connected(isConnected) {
    this.ensureBuilt();
    if (this.#source !== "video" || this.#withheld) return; // nothing to say of a picture drawn here, or withheld
    this.#stage.classList.toggle("camera__stage--stale", !isConnected);
    if (!isConnected && this.#lastHeader) {
      this.#placeholder.textContent = t("Video paused: the camera connection is down.");
      this.#placeholder.hidden = false;
    }
  }

  /** One binary message from the camera socket. Only the newest waiting frame is kept. */
  set frame(buffer) {
    this.ensureBuilt();
    if (this.#source !== "video") return; // a frame still on its way when the picture was switched
    if (this.#decoding) {
      this.#pending = buffer;
      return;
    }
    this.#decode(buffer);
  }

  /** The robot's description: the camera's size and field of view. */
  set info(info) {
    this.#feedback.setInfo(info);
    this.#requestDraw();
  }

  /** The drive socket's "ready" message: its sequence_base maps frames' sequences to ours. */
  set driveReady(message) {
    this.#feedback.reset(message?.sequence_base);
  }

  /** A message just sent on the drive socket: the picture moves at once. */
  set driveSent(message) {
    this.#feedback.recordSent(message, performance.now());
    this.#requestDraw();
  }

  set feedbackEnabled(enabled) {
    this.#feedback.enabled = Boolean(enabled);
    if (this.#feedbackToggle) this.#feedbackToggle.checked = this.#feedback.enabled;
    this.#requestDraw();
  }

  get feedbackEnabled() {
    return this.#feedback.enabled;
  }

  /** Why the motion preview cannot be switched now (the server's sentence: a delay trial sets it), or null. */
  set feedbackLocked(reason) {
    if (!this.#feedbackToggle) return;
    this.#feedbackToggle.disabled = Boolean(reason);
    if (reason) this.#feedbackToggle.setAttribute("aria-describedby", "camera-feedback-lock");
    else this.#feedbackToggle.removeAttribute("aria-describedby");
    this.#feedbackLock.textContent = reason || "";
    this.#feedbackLock.hidden = !reason;
  }

  /** "edges" or "black"; anything else is ignored (a stale saved choice must not break the view). */
  set feedbackFill(fill) {
    if (!FILL_MODES.includes(fill)) return;
    this.#feedback.fill = fill;
    if (this.#fillSelect) this.#fillSelect.value = fill;
    this.#requestDraw();
  }

  get feedbackFill() {
    return this.#feedback.fill;
  }

  /** A telemetry message: its laser scan tells how far away what the camera sees is; while the picture is drawn
   *  here, its camera pose (where the robot truly stands) is where the next frame is drawn from. */
  set telemetry(message) {
    this.#feedback.setScan(message?.laser);
    if (this.#source === "drawn" && message && "camera_pose" in message && !message.camera_pose) {
      this.source = "video";
      this.#videoNote = TRUTH_WITHHELD; // a graded run: the truth stays on the server, and so does the camera
      this.#showMessage(TRUTH_WITHHELD, false);
      this.emit("camera-source-change", { source: "video", fallback: true });
      return;
    }
    if (this.#source !== "drawn" || !this.#drawn) return;
    this.#nextPose = message;
    this.#drawSoon();
  }

  /** Draws the newest pose waiting once the previous frame is done and the frame cap allows. */
  #drawSoon() {
    if (this.#drawing || this.#poseTimer || !this.#nextPose || !this.#drawn) return;
    const waitMs = this.#frameCap.waitMs(performance.now());
    if (waitMs > 0) {
      this.#poseTimer = setTimeout(() => {
        this.#poseTimer = 0;
        this.#drawSoon();
      }, waitMs);
      return;
    }
    const message = this.#nextPose;
    this.#nextPose = null;
    this.#frameCap.drawn(performance.now());
    this.#drawFrom(message);
  }

  /** A status message from the telemetry socket: it announces an added delay as the camera socket does (the
   *  drawn picture's poses come through it, delayed alike, while the camera socket is closed). */
  set telemetryStatus(message) {
    this.ensureBuilt();
    if (message && "injected_delay_s" in message) this.#showInjectedDelay(Number(message.injected_delay_s));
  }

  /** The robot's scene description: the picture may then be drawn here. */
  set scene(scene) {
    this.ensureBuilt();
    if (!scene?.camera || scene.version === this.#scene?.version) return;
    this.#scene = scene;
    if (scene.obstacles_hidden) this.#showMessage(String(scene.obstacles_hidden), false); // the drawn picture's too
    this.#drawn?.dispose();
    this.#drawn = null;
    this.#sourceSelect.querySelector('option[value="drawn"]').disabled = false;
    if (this.#source === "drawn") this.#startDrawn();
  }

  /** "video" (the robot's JPEG stream) or "drawn" (drawn by this browser); anything else is ignored. */
  set source(source) {
    this.ensureBuilt();
    if (!SOURCES.includes(source)) return;
    this.#source = source;
    this.#videoNote = "";
    this.#videoNoteIsProblem = false;
    this.#sourceSelect.value = source;
    this.dataset.source = source;
    this.#nextPose = null;
    this.#applyWords();
    if (source === "drawn") this.#startDrawn();
  }

  get source() {
    return this.#source;
  }

  async #startDrawn() {
    if (this.#drawn || !this.#scene) return;
    const scene = this.#scene;
    const scale = Math.min(window.devicePixelRatio || 1, isSmallScreen() ? 1 : 2); // the camera's own size on a phone
    const { view, problem } = await DrawnView.create(scene, scale);
    if (scene !== this.#scene) {
      view?.dispose();
      return;
    }
    this.#drawn = view;
    this.#drawnProblem = problem;
    if (!view) {
      const option = this.#sourceSelect.querySelector('option[value="drawn"]');
      option.disabled = true;
      option.textContent = t("drawn here (WebGL is missing)");
      this.source = "video";
      this.#videoNote = problem; // outlasts the video's "live", which the fallback's own camera socket soon says
      this.#videoNoteIsProblem = true;
      this.#showMessage(problem, true);
      this.emit("camera-source-change", { source: "video", fallback: true });
    }
  }

  async #drawFrom(message) {
    this.#drawing = true;
    try {
      const frame = await this.#drawn.frameFrom(message);
      if (frame && this.#source === "drawn") this.#draw(frame.bitmap, frame.header);
      else frame?.bitmap.close();
    } catch (error) {
      console.warn("drawn frame skipped:", error.message);
    } finally {
      this.#drawing = false;
      this.#drawSoon();
    }
  }

  /** A text message from the camera socket: {type: "status"|"error", ...}. */
  set message(message) {
    this.ensureBuilt();
    if (message && "injected_delay_s" in message) this.#showInjectedDelay(Number(message.injected_delay_s));
    if (message?.type === "status" && !("robot_online" in message)) return;
    if (message?.type === "status") {
      const offline = message.robot_online === false;
      const said = message.injected_delay_s > 0 // the server says it in English; the page in its own language
        ? t("An added delay of {seconds} s is on your video.", { seconds: number(Number(message.injected_delay_s)) })
        : t(message.message ?? "");
      const online = this.#videoNote || said; // why the video shows outlasts its "live"
      this.#showMessage(offline ? said || t("The robot is offline.") : online,
        offline || (Boolean(this.#videoNote) && this.#videoNoteIsProblem));
      this.#placeholder.textContent = offline ? t("No video: the robot is offline.") : WORDS.video.waiting;
      if (offline) {
        this.#placeholder.hidden = false;
        this.#stage.classList.add("camera__stage--stale");
      }
    } else if (message?.type === "error" && message.code === WITHHELD_CODE) {
      this.#withhold(message.message);
    } else if (message?.type === "error") {
      this.#showMessage(message.message || t("The camera stream reported an error."), true);
    }
  }

  /** The server withholds the picture (the viewer's obstacle-zone test): its sentence stands where the picture
   *  was, and the last frame goes, since it shows what the test hides. */
  #withhold(text) {
    this.#withheld = true;
    this.#bitmap?.close();
    this.#bitmap = null;
    this.#pending = null;
    this.#lastHeader = null;
    this.#canvas.getContext("2d")?.clearRect(0, 0, this.#canvas.width, this.#canvas.height);
    this.#placeholder.textContent = text;
    this.#placeholder.hidden = false;
    this.#stage.classList.add("camera__stage--stale");
    this.dataset.withheld = WITHHELD_CODE; // for tools and tests
  }

  #applyLabel() {
    this.#canvas?.setAttribute("aria-label", this.#source === "drawn"
      ? t("The view of {value}, drawn by this browser from where it stands", { value: this.#robotName || t("the robot") })
      : t("Live camera of {value}", { value: this.#robotName || t("the robot") }));
  }

  /** The panel's words for its picture: the video's, or those of a view drawn here (neither video nor live). */
  #applyWords() {
    const words = WORDS[this.#source];
    this.#ageLabel.textContent = words.age;
    this.#delayLabel.textContent = words.delay;
    if (!this.#lastHeader || Boolean(this.#lastHeader.drawn_here) !== (this.#source === "drawn")) {
      this.#placeholder.textContent = words.waiting;
    }
    this.#applyLabel();
  }

  #showMessage(text, isProblem) {
    this.showMessage(text);
    this.#messageLine.classList.toggle("camera__message--problem", Boolean(isProblem));
  }

  async #decode(buffer) {
    this.#decoding = true;
    try {
      const { header, jpeg } = parseFramePacket(buffer);
      const bitmap = await createImageBitmap(new Blob([jpeg], { type: "image/jpeg" }));
      this.#draw(bitmap, header);
    } catch (error) {
      // One bad frame must not stop the stream; the next one replaces it anyway.
      console.warn("camera frame skipped:", error.message);
    } finally {
      this.#decoding = false;
      const next = this.#pending;
      this.#pending = null;
      if (next) this.#decode(next);
    }
  }

  #showInjectedDelay(seconds) {
    const active = Number.isFinite(seconds) && seconds > 0;
    const shown = this.#injectedBadge.textContent;
    this.#injectedBadge.hidden = !active;
    this.#injectedBadge.textContent = active ? t("Added delay {seconds} s", { seconds: fixed(seconds, 1) }) : "";
    // A delay begun or ended (a delay trial, a tutor's): the preview's lock may have changed with it.
    if (this.#injectedBadge.textContent !== shown) this.emit("camera-injected-delay-change", { delay_s: seconds });
  }

  #requestDraw() {
    if (this.#bitmap) this.scheduleRender();
  }

  render() {
    if (!this.#bitmap) return;
    const moving = this.#feedback.draw(this.#canvas, this.#bitmap, performance.now());
    // While predicted motion continues the picture keeps moving, frame or no frame.
    if (moving) this.scheduleRender();
  }

  #draw(bitmap, header) {
    if (this.#withheld && !header.drawn_here) { // a video frame decoded after the refusal came
      bitmap.close();
      return;
    }
    const canvas = this.#canvas;
    if (canvas.width !== bitmap.width || canvas.height !== bitmap.height) {
      canvas.width = bitmap.width;
      canvas.height = bitmap.height;
    }
    this.#bitmap?.close();
    this.#bitmap = bitmap;
    this.#feedback.recordFrame(header, performance.now());
    this.#feedback.draw(canvas, bitmap, performance.now());
    this.#requestDraw();
    this.#placeholder.hidden = true;
    this.#stage.classList.remove("camera__stage--stale");
    this.#lastHeader = header;
    this.dataset.frameSource = header.drawn_here ? "drawn" : "video"; // for tools and tests
    this.dispatchEvent(new CustomEvent("camera-frame-shown", { detail: {
      source: this.dataset.frameSource, capture_unix_s: Number(header.capture_unix_s), shown_unix_s: Date.now() / 1000,
    } }));
    const now = performance.now();
    this.#drawTimesMs.push(now);
    this.#drawTimesMs = this.#drawTimesMs.filter((t) => now - t <= FPS_WINDOW_MS);
    this.#showStats();
  }

  #showStats() {
    this.#fpsOutput.textContent = String(framesInWindow(this.#drawTimesMs, performance.now(), FPS_WINDOW_MS));
    const header = this.#lastHeader;
    if (!header) return;
    const captureS = Number(header.capture_unix_s);
    if (Number.isFinite(captureS)) {
      this.#ageOutput.textContent = String(Math.max(0, Math.round(Date.now() - captureS * 1000)));
    }
    if (Number.isFinite(Number(header.frame_sequence))) this.#sequenceOutput.textContent = String(header.frame_sequence);
    const delayMs = this.#feedback.videoDelayMs(header, Date.now());
    this.#delayOutput.textContent = Number.isFinite(delayMs) ? fixed(delayMs / 1000, 2) : "—";
  }
}

export const register = registerPanel({
  kind: "camera", tag: "camera-panel", element: CameraPanel, span: 2,
  stylesheets: [new URL("./camera-panel.css", import.meta.url)],
  // The laser scan in the telemetry gives the motion preview the depth of what the camera sees.
  feeds: [{ service: "camera-stream" }, { robotInfo: "info" }, { service: "scene" },
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "telemetryStatus" } }],
});
