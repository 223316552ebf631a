// <drive-pad>: press-and-hold driving with arrow keys, on-screen buttons (pointer, touch, Enter/Space)
// and a speed slider. It only expresses intent; the server enforces limits, lease and deadman.
// In: `limits` ({max_linear_mps, max_angular_radps}), `link` ("connecting"|"ready"|"closed"),
//     `ack`, `error` (server messages).
// Out: "drive-command" (detail: {linear_mps, angular_radps}, sent whenever the intent changes),
//      "drive-stop" (stop now: Stop button, Escape, window blur, hidden tab, page hide).

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";
import { driveCommand, KEY_DIRECTIONS } from "../../js/drive-math.js";

const SVG_NS = "http://www.w3.org/2000/svg";
const BUTTONS = [
  { direction: "forward", label: "Forward", area: "up", path: "M12 5 19 15H5z" },
  { direction: "left", label: "Turn left", area: "left", path: "M5 12 15 5v14z" },
  { direction: "stop", label: "Stop", area: "stop", path: "M7 7h10v10H7z" },
  { direction: "right", label: "Turn right", area: "right", path: "M19 12 9 19V5z" },
  { direction: "backward", label: "Backward", area: "down", path: "M12 19 5 9h14z" },
];
const BUTTON_ACTIVATION_KEYS = new Set(["Enter", " "]);
const NON_TEXT_INPUT_TYPES = new Set(["button", "submit", "reset", "checkbox", "radio", "image"]);

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
  if (element.tagName === "TEXTAREA" || element.tagName === "SELECT") return true;
  if (element.tagName === "INPUT") return !NON_TEXT_INPUT_TYPES.has(element.type);
  return false;
}

export class DrivePad extends HTMLElement {
  #built = false;
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
  #errorLine;
  #listening = false;

  connectedCallback() {
    this.#build();
    if (this.#listening) return;
    this.#listening = true;
    document.addEventListener("keydown", this.#onDocumentKeyDown);
    document.addEventListener("keyup", this.#onDocumentKeyUp);
    window.addEventListener("blur", this.#onLoseAttention);
    window.addEventListener("pagehide", this.#onLoseAttention);
    document.addEventListener("visibilitychange", this.#onVisibilityChange);
  }

  disconnectedCallback() {
    this.#listening = false;
    document.removeEventListener("keydown", this.#onDocumentKeyDown);
    document.removeEventListener("keyup", this.#onDocumentKeyUp);
    window.removeEventListener("blur", this.#onLoseAttention);
    window.removeEventListener("pagehide", this.#onLoseAttention);
    document.removeEventListener("visibilitychange", this.#onVisibilityChange);
  }

  set limits(limits) {
    this.#limits = limits ?? null;
    this.#build();
    this.#showSpeed();
    this.#emitIfChanged();
  }

  /** State of the drive socket: "connecting", "ready" (the server sent its limits) or "closed". */
  set link(state) {
    this.#build();
    this.#linkNote.hidden = state === "ready";
    this.#linkNote.textContent = state === "closed"
      ? "Driving is unavailable: the drive connection is closed."
      : "Connecting to the drive…";
  }

  /** True while someone else has control: the pad stays usable but says the robot will not obey. */
  set observing(observing) {
    this.#build();
    const wasObserving = this.hasAttribute("data-observing");
    this.toggleAttribute("data-observing", Boolean(observing));
    this.#observingNote.hidden = !observing;
    if (wasObserving && !observing) this.#setError("");  // the refusal no longer applies
  }

  set ack(message) {
    this.#build();
    this.#ackOutput.textContent = String(message?.sequence ?? "—");
    this.#appliedOutput.textContent = String(message?.applied_sequence ?? "—");
    this.#setError("");
  }

  set error(message) {
    this.#build();
    this.#setError(message?.message || (message ? "The robot refused the command." : ""));
  }

  /** Directions held by any source right now. */
  get heldDirections() {
    return new Set([...this.#heldKeys.values(), ...this.#heldButtonKeys.values(), ...this.#heldPointers.values()]);
  }

  get speedFraction() {
    return this.#slider ? Number(this.#slider.value) / 100 : 0.5;
  }

  #build() {
    if (this.#built) return;
    this.#built = true;
    this.classList.add("panel");

    const pad = h("div", { class: "pad", role: "group", "aria-label": "Drive controls", oncontextmenu: (e) => e.preventDefault() });
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
    this.#linkNote = h("p", { class: "drive__note", "data-field": "drive-link", text: "Connecting to the drive…" });
    this.#observingNote = h("p", {
      class: "drive__note drive__note--observing", "data-field": "drive-observing", hidden: true,
      text: "You are observing: the robot obeys the person whose turn it is.",
    });
    this.#ackOutput = h("span", { "data-field": "ack-sequence", text: "—" });
    this.#appliedOutput = h("span", { "data-field": "applied-sequence", text: "—" });
    this.#errorLine = h("p", { class: "drive__error", "data-field": "drive-error", role: "alert", hidden: true });

    this.append(
      h("h2", { class: "panel__title", id: "drive-title", text: "Drive" }),
      this.#linkNote,
      this.#observingNote,
      pad,
      h("div", { class: "drive__speed" },
        h("label", { for: "drive-speed", text: "Speed" }),
        this.#slider,
        this.#speedOutput),
      h("p", { class: "drive__hint" },
        "Hold the arrow keys or the buttons to drive; let go to stop. ",
        h("kbd", { text: "Esc" }), " stops."),
      h("p", { class: "drive__acks" },
        "Last acknowledged command ", this.#ackOutput, " · applied ", this.#appliedOutput),
      this.#errorLine,
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
    if (!direction || event.altKey || event.ctrlKey || event.metaKey) return;
    if (focusWantsArrowKeys(document.activeElement)) return;
    event.preventDefault(); // no page scrolling while driving
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
    this.#heldKeys.clear();
    this.#heldButtonKeys.clear();
    this.#heldPointers.clear();
    this.#showActive();
    this.#lastEmitted = { linear_mps: 0, angular_radps: 0 };
    this.dispatchEvent(new CustomEvent("drive-stop", { bubbles: true }));
  }

  #changed() {
    this.#showActive();
    this.#emitIfChanged();
  }

  #emitIfChanged() {
    const command = driveCommand(this.heldDirections, this.speedFraction, this.#limits);
    const last = this.#lastEmitted;
    if (command.linear_mps === last.linear_mps && command.angular_radps === last.angular_radps) return;
    this.#lastEmitted = command;
    this.dispatchEvent(new CustomEvent("drive-command", { bubbles: true, detail: command }));
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
    this.#slider.setAttribute("aria-valuetext", `${percent} percent`);
    const linear = this.#limits ? (fraction * this.#limits.max_linear_mps).toFixed(2) : null;
    const angular = this.#limits ? (fraction * this.#limits.max_angular_radps).toFixed(2) : null;
    this.#speedOutput.textContent = linear === null
      ? `${percent} %`
      : `${percent} % · ${linear} m/s · ${angular} rad/s`;
  }

  #setError(text) {
    if (this.#errorLine.textContent === text && this.#errorLine.hidden === !text) return;
    this.#errorLine.textContent = text;
    this.#errorLine.hidden = !text;
  }
}

export function register() {
  adoptStylesheet(new URL("./drive-pad.css", import.meta.url));
  defineOnce("drive-pad", DrivePad);
}
