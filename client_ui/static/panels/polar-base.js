// The polar view that the sonar and laser panels share: a round canvas with forward up (range rings, the
// robot in the middle), a summary line in words, a table of readings under a disclosure and a message line.
// A subclass says what it shows (`polarView()`), keeps its readings, and in `render()` fills the summary and
// table and calls `drawPolar(maxRange, ringStep, drawReadings)`.

import { h } from "../lib/dom.js";
import { PanelElement } from "./panel-base.js";

export const POLAR_STYLESHEET = new URL("./polar-base.css", import.meta.url);

const RING_COLOUR = "#d3d9e1";
const ROBOT_COLOUR = "#1d5fc4";

export class PolarPanel extends PanelElement {
  #canvas;
  #tableBody;

  /**
   * What the view shows; called once, when the panel is built.
   *
   * @returns {{title: string, canvasLabel: string, summaryId: string, summaryAttrs?: object,
   *            summary: (string|Node)[], details: string, caption: string, columns: string[]}}
   */
  polarView() {
    throw new Error("a polar panel must describe its view");
  }

  build() {
    const view = this.polarView();
    this.classList.add("panel", "polar");
    this.#canvas = h("canvas", { class: "polar__canvas", width: 260, height: 260, role: "img",
      "aria-label": view.canvasLabel, "aria-describedby": view.summaryId });
    this.#tableBody = h("tbody");
    this.append(
      h("h2", { class: "panel__title", text: view.title }),
      this.#canvas,
      h("p", { class: "polar__summary", id: view.summaryId, ...view.summaryAttrs }, ...view.summary),
      h("details", { class: "polar__details" }, h("summary", { text: view.details }),
        h("table", { class: "polar__table" },
          h("caption", { class: "visually-hidden", text: view.caption }),
          h("thead", {}, h("tr", {}, view.columns.map((column) => h("th", { scope: "col", text: column })))),
          this.#tableBody)),
      this.messageLine({ class: "polar__message" }),
    );
  }

  /** The readings table's body, for the subclass to fill. */
  get readingsBody() {
    this.ensureBuilt();
    return this.#tableBody;
  }

  /**
   * Size the canvas to its CSS box, draw the range rings every ringStep metres out to maxRange, let
   * drawReadings(ctx, centre, scale, size) draw the readings, and the robot on top.
   */
  drawPolar(maxRange, ringStep, drawReadings) {
    const canvas = this.#canvas;
    const size = Math.round((canvas.clientWidth || 260) * (window.devicePixelRatio || 1));
    if (canvas.width !== size) { canvas.width = size; canvas.height = size; }
    const ctx = canvas.getContext("2d");
    const c = size / 2;
    const scale = (size / 2 - 6) / maxRange;
    ctx.clearRect(0, 0, size, size);
    ctx.strokeStyle = RING_COLOUR;
    ctx.lineWidth = 1;
    for (let r = ringStep; r <= maxRange; r += ringStep) { ctx.beginPath(); ctx.arc(c, c, r * scale, 0, 2 * Math.PI); ctx.stroke(); }
    drawReadings(ctx, c, scale, size);
    ctx.fillStyle = ROBOT_COLOUR;
    ctx.beginPath();
    ctx.moveTo(c, c - 10); ctx.lineTo(c - 7, c + 7); ctx.lineTo(c + 7, c + 7);
    ctx.fill();
  }

  /** Show the nearest reading: its words in `field`, its range in data-nearest-m (for tests and scripts). */
  showNearest(field, nearest, words) {
    field.textContent = words;
    this.dataset.nearestM = nearest ? nearest.range_m.toFixed(3) : ""; // data, not text: a data attribute
  }
}
