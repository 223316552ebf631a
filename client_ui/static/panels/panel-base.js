// The small base every panel shares, so no panel re-implements it: children built once on first use (custom
// elements may not add children in their constructor), a message line for the server's status and error
// sentences, and drawing at most once per animation frame however fast the data comes.
// Data comes in through properties; actions go out as CustomEvents (see `emit`); text only as text nodes.

import { adoptStylesheet, defineOnce, h } from "../lib/dom.js";
import { t } from "../lib/i18n.js";

export class PanelElement extends HTMLElement {
  #built = false;
  #frame = 0;
  #renderWanted = false;
  #messageLine = null;

  connectedCallback() {
    this.ensureBuilt();
    if (this.#renderWanted) this.scheduleRender(); // a move in the grid disconnects and reconnects the panel
  }

  disconnectedCallback() {
    cancelAnimationFrame(this.#frame);
    this.#frame = 0;
  }

  /** Build the panel's children if that has not happened yet; every property setter may call it first. */
  ensureBuilt() {
    if (this.#built) return;
    this.#built = true; // first, so that build() may use the panel's own setters
    if (this.build() === false) this.#built = false;
  }

  /** Subclasses add their children here, once; returning false means "not yet" (asked again on next use). */
  build() {}

  /** Throw the children away and build them again (a panel whose shape follows its data). */
  rebuild() {
    this.#built = false;
    this.replaceChildren();
    this.ensureBuilt();
  }

  /** Ask for one `render()` on the next animation frame; many calls before it come to one render. */
  scheduleRender() {
    this.#renderWanted = true;
    if (this.#frame) return;
    this.#frame = requestAnimationFrame(() => {
      this.#frame = 0;
      this.#renderWanted = false;
      this.ensureBuilt();
      this.render();
    });
  }

  /** Subclasses draw here, at most once per animation frame. */
  render() {}

  /** The panel's message line (hidden while empty); `attrs` give its class and data-field. */
  messageLine(attrs = {}) {
    this.#messageLine = h("p", { ...attrs, hidden: true });
    return this.#messageLine;
  }

  /** Show `text` (as text) in the message line, or hide the line when there is none. */
  showMessage(text) {
    this.ensureBuilt();
    const line = this.#messageLine;
    if (!line || (line.textContent === (text || "") && line.hidden === !text)) return; // no second announcement
    line.textContent = text || "";
    line.hidden = !text;
  }

  /** A status or error message from the panel's socket: its sentence goes to the message line. */
  set message(message) {
    this.showMessage(t(message?.message ?? ""));  // the server's fixed words ("live") are in the catalogue
  }

  /** Send an action out of the panel, as a bubbling CustomEvent the console's wiring listens to. */
  emit(type, detail) {
    this.dispatchEvent(new CustomEvent(type, { detail, bubbles: true }));
  }
}

/** A register() for a custom element: adds its stylesheets to the page once and defines the tag once. */
export function elementRegistrar(tag, elementClass, stylesheets = []) {
  return () => {
    for (const url of stylesheets) adoptStylesheet(url);
    defineOnce(tag, elementClass);
  };
}
