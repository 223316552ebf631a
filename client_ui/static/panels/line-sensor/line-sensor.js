// <line-sensor-panel>: the downward line sensor (a row of reflectance cells under the robot's front, left to right):
// each cell drawn as a square, dark as the tape it sees, with its reading, and where the line is in words.
// In: `info` (robot info with `line_sensor`: {ahead_m, offsets_m}), `telemetry` ({line: {values}}), `message`.
// Out: none.

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

const SEEN = 0.5;

/** Where the tape is under the cells, in words; pure. offsets are left-positive metres, values 0..1. */
export function lineWords(values, offsets) {
  if (!values.length) return t("This scene has no line to read.");
  const seen = values.map((value, index) => [value, Number(offsets[index]) || 0]).filter(([value]) => value > SEEN);
  if (!seen.length) return t("No line under the sensor.");
  const offset = seen.reduce((sum, [value, at]) => sum + value * at, 0) / seen.reduce((sum, [value]) => sum + value, 0);
  const cm = fixed(Math.abs(offset * 100), 1);
  if (Math.abs(offset) < 0.005) return t("Line under the middle.");
  return offset > 0 ? t("Line {cm} cm to the left.", { cm }) : t("Line {cm} cm to the right.", { cm });
}

export class LineSensorPanel extends PanelElement {
  #cells;
  #words;
  #offsets = [];
  #values = [];

  build() {
    this.classList.add("panel");
    this.#cells = h("ol", { class: "line-sensor__cells", "aria-label": t("Line sensor cells, left to right") });
    this.#words = h("p", { class: "line-sensor__words", "data-field": "line-position", "aria-live": "off", text: "—" });
    this.append(h("h2", { class: "panel__title", text: t("Line sensor") }), this.#cells, this.#words,
      h("p", { class: "line-sensor__help", text: t("1 over the tape, 0 on bare floor.") }),
      this.messageLine({ class: "line-sensor__message", "data-field": "line-message" }));
  }

  set info(info) {
    this.ensureBuilt();
    this.#offsets = Array.isArray(info?.line_sensor?.offsets_m) ? info.line_sensor.offsets_m.map(Number) : [];
    this.scheduleRender();
  }

  set telemetry(message) {
    const values = message?.line?.values;
    if (!Array.isArray(values)) return;
    this.#values = values.map(Number);
    this.scheduleRender();
  }

  render() {
    const count = Math.max(this.#values.length, this.#offsets.length);
    if (this.#cells.children.length !== count) {
      this.#cells.replaceChildren(...Array.from({ length: count }, (_, index) => h("li", { class: "line-sensor__cell",
        "data-line-cell": String(index) }, h("span", { class: "line-sensor__patch" }),
        h("span", { class: "line-sensor__value", text: "—" }))));
    }
    [...this.#cells.children].forEach((cell, index) => {
      const value = this.#values[index];
      const known = Number.isFinite(value);
      cell.querySelector(".line-sensor__patch").style.setProperty("--tape", known ? String(value) : "0");
      cell.querySelector(".line-sensor__value").textContent = known ? fixed(value, 2) : "—";
      cell.toggleAttribute("data-on-line", known && value > SEEN);
    });
    this.#words.textContent = lineWords(this.#values, this.#offsets);
  }
}

export const register = registerPanel({
  kind: "line-sensor", tag: "line-sensor-panel", element: LineSensorPanel,
  stylesheets: [new URL("./line-sensor.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "message", error: "message" } },
    { robotInfo: "info", fields: ["line_sensor"] },
  ],
});
