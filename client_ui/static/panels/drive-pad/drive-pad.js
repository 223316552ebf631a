// <drive-pad>: press-and-hold driving with arrow keys, on-screen buttons (pointer, touch, Enter/Space)
// and a speed slider. It only expresses intent; the server enforces limits, lease and deadman.
// In: `limits` ({max_linear_mps, max_angular_radps}), `link` ("connecting"|"ready"|"closed"),
//     `ack`, `error` (server messages).
// Modes: press-and-hold (drive while held) and step (each press drives a fixed step, timed client-side).
// Devices: keyboard, on-screen buttons (pointer/touch/keys) and a gamepad (left stick, A/B stop).
// Out: "drive-command" (detail: {linear_mps, angular_radps}, sent whenever the intent changes),
//      "drive-stop" (stop now: Stop button, Escape, window blur, hidden tab, page hide).

import { h } from "../../lib/dom.js";
import { driveCommand, isStill, KEY_DIRECTIONS, stickCommand, stepCommand } from "../../lib/drive-math.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

const SVG_NS = "http://www.w3.org/2000/svg";
const BUTTONS = [
  { direction: "forward", label: t("Forward"), area: "up", path: "M12 5 19 15H5z" },
  { direction: "left", label: t("Turn left"), area: "left", path: "M5 12 15 5v14z" },
  { direction: "stop", label: t("Stop"), area: "stop", path: "M7 7h10v10H7z" },
  { direction: "right", label: t("Turn right"), area: "right", path: "M19 12 9 19V5z" },
  { direction: "backward", label: t("Backward"), area: "down", path: "M12 19 5 9h14z" },
];
const BUTTON_ACTIVATION_KEYS = new Set(["Enter", " "]);
const NON_TEXT_INPUT_TYPES = new Set(["button", "submit", "reset", "checkbox", "image"]);
const STOP_BUTTONS = [0, 1]; // standard mapping: A / B (cross / circle) stop the robot

function icon(path) {
  const svg = document.createElementNS(SVG_NS, "svg");
  svg.setAttribute("viewBox", "0 0 24 24");
  svg.setAttribute("aria-hidden", "true");
  svg.setAttribute("focusable", "false");
  const shape = document.createElementNS(SVG_NS, "path");
  shape.setAttribute("d", path);
  svg.append(shape);
  return svg;
}

/** True when arrow keys belong to the focused element (typing, sliders, selects). */
function focusWantsArrowKeys(element) {
  if (!element) return false;
  if (element.isContentEditable) return true;
  // Panels that use the arrow keys themselves (the map's cursor) say so with this attribute.
  if (element.closest?.("[data-wants-arrow-keys]")) return true;
  if (element.tagName === "TEXTAREA" || element.tagName === "SELECT") return true;
  if (element.tagName === "INPUT") return !NON_TEXT_INPUT_TYPES.has(element.type);
  return false;
}

export class DrivePad extends PanelElement {
  #limits = null;
  #heldKeys = new Map();        // arrow key -> direction
  #heldButtonKeys = new Map();  // "Enter"/" " on a focused pad button -> direction
  #heldPointers = new Map();    // pointerId -> direction
  #lastEmitted = { linear_mps: 0, angular_radps: 0 };
  #buttons = new Map();
  #slider;
  #speedOutput;
  #linkNote;
  #observingNote;
  #ackOutput;
  #appliedOutput;
  #listening = false;
  #mode = "hold";
  #stepTimer = 0;
  #gamepadIndex = null;
  #gamepadCommand = { linear_mps: 0, angular_radps: 0 };
  #gamepadStopWasPressed = false;
  #gamepadFrame = 0;
  #gamepadNote;
  #modeNote;

  connectedCallback() {
    super.connectedCallback();
    if (this.#listening) return;
    this.#listening = true;
    document.addEventListener("keydown", this.#onDocumentKeyDown);
    document.addEventListener("keyup", this.#onDocumentKeyUp);
    window.addEventListener("blur", this.#onLoseAttention);
    window.addEventListener("pagehide", this.#onLoseAttention);
    document.addEventListener("visibilitychange", this.#onVisibilityChange);
    window.addEventListener("gamepadconnected", this.#onGamepadConnected);
    window.addEventListener("gamepaddisconnected", this.#onGamepadDisconnected);
  }

  disconnectedCallback() {
    super.disconnectedCallback();
    window.removeEventListener("gamepadconnected", this.#onGamepadConnected);
    window.removeEventListener("gamepaddisconnected", this.#onGamepadDisconnected);
    cancelAnimationFrame(this.#gamepadFrame);
    clearTimeout(this.#stepTimer);
    this.#listening = false;
    document.removeEventListener("keydown", this.#onDocumentKeyDown);
    document.removeEventListener("keyup", this.#onDocumentKeyUp);
    window.removeEventListener("blur", this.#onLoseAttention);
    window.removeEventListener("pagehide", this.#onLoseAttention);
    document.removeEventListener("visibilitychange", this.#onVisibilityChange);
  }

  set limits(limits) {
    this.#limits = limits ?? null;
    this.ensureBuilt();
    this.#showSpeed();
    this.#emitIfChanged();
  }

  /** State of the drive socket: "connecting", "ready" (the server sent its limits) or "closed". */
  set link(state) {
    this.ensureBuilt();
    this.#linkNote.hidden = state === "ready";
    this.#linkNote.textContent = state === "closed"
      ? t("Driving is unavailable: the drive connection is closed.")
      : t("Connecting to the drive…");
  }

  /** True while someone else has control: the pad stays usable but says the robot will not obey. */
  set observing(observing) {
    this.ensureBuilt();
    const wasObserving = this.hasAttribute("data-observing");
    this.toggleAttribute("data-observing", Boolean(observing));
    this.#observingNote.hidden = !observing;
    if (wasObserving && !observing) this.#setError("");  // the refusal no longer applies
  }

  set ack(message) {
    this.ensureBuilt();
    this.#ackOutput.textContent = String(message?.sequence ?? "—");
    this.#appliedOutput.textContent = String(message?.applied_sequence ?? "—");
    this.#setError("");
  }

  set error(message) {
    this.ensureBuilt();
    this.#setError(message?.message || (message ? t("The robot refused the command.") : ""));
  }

  /** Directions held by any source right now. */
  get heldDirections() {
    return new Set([...this.#heldKeys.values(), ...this.#heldButtonKeys.values(), ...this.#heldPointers.values()]);
  }

  /** "hold" (drive while pressed) or "step" (each press moves a fixed step). */
  get mode() {
    return this.#mode;
  }

  set mode(mode) {
    this.ensureBuilt();
    this.#mode = mode === "step" ? "step" : "hold";
    for (const radio of this.querySelectorAll('input[name="drive-mode"]')) radio.checked = radio.value === this.#mode;
    this.#modeNote.textContent = this.#mode === "step"
      ? t("Step mode: each press drives 0.1 m or turns 15°. The browser drives at the chosen speed for as long as that step takes, then stops, so acceleration makes steps a little short.")
      : t("Hold the arrow keys or the buttons to drive; let go to stop.");
    this.#stopAll();
  }

  get speedFraction() {
    return this.#slider ? Number(this.#slider.value) / 100 : 0.5;
  }

  build() {
    this.classList.add("panel");

    const pad = h("div", { class: "pad", role: "group", "aria-label": t("Drive controls"), oncontextmenu: (e) => e.preventDefault() });
    for (const spec of BUTTONS) {
      const button = h("button", {
        type: "button",
        class: `pad__button pad__button--${spec.area}`,
        "aria-label": spec.label,
        "data-drive": spec.direction,
        title: spec.label,
      }, icon(spec.path));
      this.#wireButton(button, spec.direction);
      this.#buttons.set(spec.direction, button);
      pad.append(button);
    }

    this.#slider = h("input", {
      type: "range", id: "drive-speed", min: 10, max: 100, step: 10, value: 50,
      "aria-describedby": "drive-speed-value",
      oninput: () => { this.#showSpeed(); this.#emitIfChanged(); },
    });
    this.#speedOutput = h("output", { id: "drive-speed-value", for: "drive-speed", class: "drive__speed-value" });
    this.#linkNote = h("p", { class: "drive__note", "data-field": "drive-link", text: t("Connecting to the drive…") });
    this.#observingNote = h("p", {
      class: "drive__note drive__note--observing", "data-field": "drive-observing", hidden: true,
      text: t("You are observing: the robot obeys the person whose turn it is."),
    });
    this.#ackOutput = h("span", { "data-field": "ack-sequence", text: "—" });
    this.#appliedOutput = h("span", { "data-field": "applied-sequence", text: "—" });

    this.append(
      h("h2", { class: "panel__title", id: "drive-title", text: t("Drive") }),
      this.#linkNote,
      this.#observingNote,
      pad,
      h("div", { class: "drive__speed" },
        h("label", { for: "drive-speed", text: t("Speed") }),
        this.#slider,
        this.#speedOutput),
      h("fieldset", { class: "drive__modes" },
        h("legend", { text: t("Mode") }),
        ["hold", "step"].map((value) => h("label", { class: "drive__mode" },
          h("input", { type: "radio", name: "drive-mode", value, checked: value === "hold",
            onchange: () => { this.mode = value; } }),
          value === "hold" ? t(" Press and hold") : t(" Step")))),
      h("p", { class: "drive__hint" },
        this.#modeNote = h("span", { "data-field": "drive-mode-note",
          text: t("Hold the arrow keys or the buttons to drive; let go to stop.") }), " ",
        h("kbd", { text: t("Esc") }), t(" stops.")),
      this.#gamepadNote = h("p", { class: "drive__note", "data-field": "gamepad", hidden: true }),
      h("p", { class: "drive__acks" },
        t("Last acknowledged command "), this.#ackOutput, t(" · applied "), this.#appliedOutput),
      this.messageLine({ class: "drive__error", "data-field": "drive-error", role: "alert" }),
    );
    this.#showSpeed();
  }

  #wireButton(button, direction) {
    if (direction === "stop") {
      button.addEventListener("pointerdown", () => this.#stopAll());
      // detail 0 marks a click made with Enter/Space; pointer clicks already stopped on pointerdown.
      button.addEventListener("click", (event) => { if (event.detail === 0) this.#stopAll(); });
      return;
    }
    button.addEventListener("pointerdown", (event) => {
      if (event.pointerType === "mouse" && event.button !== 0) return;
      // Touch captures the pointer implicitly; releasing it lets "pointerleave" fire when the
      // finger slides off the button, so the robot stops instead of driving on.
      if (button.hasPointerCapture?.(event.pointerId)) button.releasePointerCapture(event.pointerId);
      if (this.#mode === "step") {
        this.#step(direction);
        return;
      }
      this.#heldPointers.set(event.pointerId, direction);
      this.#changed();
    });
    const release = (event) => {
      if (this.#heldPointers.delete(event.pointerId)) this.#changed();
    };
    for (const type of ["pointerup", "pointercancel", "pointerleave"]) button.addEventListener(type, release);

    button.addEventListener("keydown", (event) => {
      if (!BUTTON_ACTIVATION_KEYS.has(event.key)) return;
      event.preventDefault();
      if (event.repeat) return;
      if (this.#mode === "step") {
        this.#step(direction);
        return;
      }
      this.#heldButtonKeys.set(event.key, direction);
      this.#changed();
    });
    button.addEventListener("keyup", (event) => {
      if (!BUTTON_ACTIVATION_KEYS.has(event.key)) return;
      event.preventDefault();
      if (this.#heldButtonKeys.delete(event.key)) this.#changed();
    });
    button.addEventListener("blur", () => {
      if (this.#heldButtonKeys.size === 0) return;
      this.#heldButtonKeys.clear();
      this.#changed();
    });
  }

  #onDocumentKeyDown = (event) => {
    if (event.key === "Escape") {
      this.#onLoseAttention();
      return;
    }
    const direction = KEY_DIRECTIONS[event.key];
    if (!direction || event.altKey || event.ctrlKey || event.metaKey || event.defaultPrevented) return;
    if (focusWantsArrowKeys(document.activeElement)) return;
    event.preventDefault(); // no page scrolling while driving
    if (this.#mode === "step") {
      if (!event.repeat) this.#step(direction);
      return;
    }
    if (this.#heldKeys.has(event.key)) return;
    this.#heldKeys.set(event.key, direction);
    this.#changed();
  };

  #onDocumentKeyUp = (event) => {
    // Released keys always count, wherever focus went meanwhile, so a key can never stay "stuck".
    if (this.#heldKeys.delete(event.key)) this.#changed();
  };

  // Only when driving: a stop sent by an idle page could land in someone else's turn as an error.
  #onLoseAttention = () => {
    if (this.heldDirections.size > 0 || !this.#isStill(this.#lastEmitted)) this.#stopAll();
  };

  #onVisibilityChange = () => {
    if (document.visibilityState === "hidden") this.#onLoseAttention();
  };

  #stopAll() {
    clearTimeout(this.#stepTimer);
    this.#stepTimer = 0;
    this.removeAttribute("data-stepping");
    this.#heldKeys.clear();
    this.#heldButtonKeys.clear();
    this.#heldPointers.clear();
    this.#showActive();
    this.#lastEmitted = { linear_mps: 0, angular_radps: 0 };
    this.emit("drive-stop", null);
  }

  #changed() {
    this.#showActive();
    this.#emitIfChanged();
  }

  /** One step: drive at the chosen speed for the step's duration, then stop. Presses during a step are ignored. */
  #step(direction) {
    if (direction === "stop" || this.#stepTimer) return;
    const step = stepCommand(direction, this.speedFraction, this.#limits);
    if (!step) {
      this.#setError(t("A step needs a speed above 0 and the robot's limits; wait for the drive to connect."));
      return;
    }
    this.toggleAttribute("data-stepping", true);
    this.#lastEmitted = step.command;
    this.emit("drive-command", step.command);
    this.#stepTimer = setTimeout(() => {
      this.#stepTimer = 0;
      this.removeAttribute("data-stepping");
      this.#lastEmitted = { linear_mps: 0, angular_radps: 0 };
      this.emit("drive-command", this.#lastEmitted);
    }, step.duration_ms);
  }

  #onGamepadConnected = (event) => {
    this.#gamepadIndex = event.gamepad.index;
    this.#gamepadNote.hidden = false;
    this.#gamepadNote.textContent = t("Gamepad connected ({id}): the left stick drives, A or B stops.", { id: event.gamepad.id });
    cancelAnimationFrame(this.#gamepadFrame);
    this.#gamepadFrame = requestAnimationFrame(this.#pollGamepad);
  };

  #onGamepadDisconnected = (event) => {
    if (event.gamepad.index !== this.#gamepadIndex) return;
    this.#gamepadIndex = null;
    cancelAnimationFrame(this.#gamepadFrame);
    this.#gamepadNote.textContent = t("Gamepad disconnected.");
    this.#gamepadCommand = { linear_mps: 0, angular_radps: 0 };
    this.#emitIfChanged();
  };

  // The Gamepad API has no input events: the pad is read once per animation frame while connected.
  #pollGamepad = () => {
    const pad = this.#gamepadIndex === null ? null : navigator.getGamepads?.()[this.#gamepadIndex];
    if (!pad) return;
    const stopPressed = STOP_BUTTONS.some((index) => pad.buttons[index]?.pressed);
    if (stopPressed && !this.#gamepadStopWasPressed) this.#stopAll();
    this.#gamepadStopWasPressed = stopPressed;
    this.#gamepadCommand = stopPressed ? { linear_mps: 0, angular_radps: 0 }
      : stickCommand(pad.axes, this.speedFraction, this.#limits);
    this.#emitIfChanged();
    this.#gamepadFrame = requestAnimationFrame(this.#pollGamepad);
  };

  #emitIfChanged() {
    if (this.#stepTimer) return; // a step in progress owns the wheels until it ends
    const keys = driveCommand(this.heldDirections, this.speedFraction, this.#limits);
    const command = isStill(this.#gamepadCommand) ? keys : this.#gamepadCommand;
    const last = this.#lastEmitted;
    if (command.linear_mps === last.linear_mps && command.angular_radps === last.angular_radps) return;
    this.#lastEmitted = command;
    this.emit("drive-command", command);
  }

  #isStill(command) {
    return command.linear_mps === 0 && command.angular_radps === 0;
  }

  #showActive() {
    const held = this.heldDirections;
    for (const [direction, button] of this.#buttons) {
      if (direction === "stop") continue;
      button.toggleAttribute("data-active", held.has(direction));
    }
  }

  #showSpeed() {
    if (!this.#slider) return;
    const percent = Number(this.#slider.value);
    const fraction = percent / 100;
    this.#slider.setAttribute("aria-valuetext", t("{percent} percent", { percent }));
    const linear = this.#limits ? fixed(fraction * this.#limits.max_linear_mps, 2) : null;
    const angular = this.#limits ? fixed(fraction * this.#limits.max_angular_radps, 2) : null;
    this.#speedOutput.textContent = linear === null
      ? `${percent} %`
      : t("{percent} % · {linear} m/s · {angular} rad/s", { percent, linear, angular });
  }

  #setError(text) {
    this.showMessage(text);
  }
}

export const register = registerPanel({
  kind: "drive", tag: "drive-pad", element: DrivePad, stylesheets: [new URL("./drive-pad.css", import.meta.url)],
  feeds: [{ service: "drive" }, { robotInfo: "limits", fields: ["max_linear_mps", "max_angular_radps"] }],
});
