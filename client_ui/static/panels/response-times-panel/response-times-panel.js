// <response-times-panel>: the two legs of the paper's table 1, measured live with pings on the drive socket:
// client -> middleware (browser round trip minus the robot leg) and middleware -> skill server (the gRPC
// round trip the middleware reports). Live values, a sparkline of the last samples, mean and p95.
// In: `sample` ({client_ms, robot_ms}), `unavailable` (a sentence, or "" when pings work). Out: none.

import { h } from "../../lib/dom.js";
import { summarize } from "../../lib/stats.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";

const WINDOW = 50;
const LEGS = [
  { key: "client", label: "Browser → middleware", colour: "#1d5fc4" },
  { key: "robot", label: "Middleware → skill server", colour: "#b1261b" },
];

function swatch(colour) {
  const element = h("span", { class: "rtt__swatch", "aria-hidden": "true" });
  element.style.setProperty("--swatch", colour);
  return element;
}

function ms(value) {
  return Number.isFinite(value) ? value.toFixed(1) : "—";
}

export class ResponseTimesPanel extends PanelElement {
  #series = { client: [], robot: [] };
  #cells = {};
  #canvas;
  #note;

  /** One measurement; both legs in milliseconds. */
  set sample(sample) {
    this.ensureBuilt();
    for (const { key } of LEGS) {
      const value = Number(sample?.[`${key}_ms`]);
      if (!Number.isFinite(value) || value < 0) continue;
      this.#series[key].push(value);
      if (this.#series[key].length > WINDOW) this.#series[key].shift();
    }
    this.#note.hidden = true;
    this.scheduleRender();
  }

  set unavailable(text) {
    this.ensureBuilt();
    this.#note.textContent = text || "";
    this.#note.hidden = !text;
  }

  build() {
    this.classList.add("panel", "rtt");
    const cell = (key, stat) => (this.#cells[`${key}-${stat}`] = h("td", { "data-field": `rtt-${key}-${stat}`, text: "—" }));
    this.#canvas = h("canvas", { class: "rtt__spark", width: 300, height: 60, role: "img",
      "aria-label": `Response times of the last ${WINDOW} pings` });
    this.#note = h("p", { class: "rtt__note", "data-field": "rtt-note", text: "Measuring…" });
    this.append(
      h("h2", { class: "panel__title", text: "Response times" }),
      h("table", { class: "rtt__table" },
        h("caption", { class: "visually-hidden", text: `Round trips in milliseconds, over the last ${WINDOW} pings` }),
        h("thead", {}, h("tr", {}, h("th", { scope: "col", text: "Round trip (ms)" }), h("th", { scope: "col", text: "Now" }),
          h("th", { scope: "col", text: "Mean" }), h("th", { scope: "col", text: "p95" }))),
        h("tbody", {}, LEGS.map(({ key, label, colour }) => h("tr", {},
          h("th", { scope: "row" }, swatch(colour), label),
          cell(key, "last"), cell(key, "mean"), cell(key, "p95"))))),
      this.#canvas,
      this.#note,
      h("p", { class: "rtt__help muted", text: "Measured with a ping on the drive connection once a second. "
        + "Browser → middleware is the whole round trip minus the middleware's own call to the robot." }),
    );
  }

  render() {
    for (const { key } of LEGS) {
      const summary = summarize(this.#series[key], WINDOW);
      this.#cells[`${key}-last`].textContent = ms(summary.last);
      this.#cells[`${key}-mean`].textContent = ms(summary.mean);
      this.#cells[`${key}-p95`].textContent = ms(summary.p95);
    }
    const canvas = this.#canvas;
    const width = Math.round((canvas.clientWidth || 300) * (window.devicePixelRatio || 1));
    const height = Math.round(width / 5);
    if (canvas.width !== width || canvas.height !== height) { canvas.width = width; canvas.height = height; }
    const ctx = canvas.getContext("2d");
    ctx.clearRect(0, 0, width, height);
    const top = Math.max(1, ...this.#series.client, ...this.#series.robot) * 1.1;
    ctx.lineWidth = Math.max(1.5, width / 200);
    for (const { key, colour } of LEGS) {
      const values = this.#series[key];
      ctx.strokeStyle = colour;
      ctx.beginPath();
      values.forEach((value, index) => {
        const x = width - (values.length - 1 - index) * (width / (WINDOW - 1));
        const y = height - 2 - (value / top) * (height - 4);
        if (index === 0) ctx.moveTo(x, y);
        else ctx.lineTo(x, y);
      });
      ctx.stroke();
    }
  }
}

export const register = registerPanel({
  kind: "response-times", tag: "response-times-panel", element: ResponseTimesPanel,
  stylesheets: [new URL("./response-times-panel.css", import.meta.url)],
  feeds: [{ service: "pings" }],
});
