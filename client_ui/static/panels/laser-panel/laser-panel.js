// <laser-panel>: a polar view of the laser scan (forward is up), with the nearest hit in words and the
// nearest hit per sector in a table. In: `info` (robot info with `laser`), `telemetry`, `message`. Out: none.

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";
import { describeBearing, isEcho, laserBearings, nearestReading, polarToScreen, sectorMinima } from "../../js/polar.js";

const SECTORS = 8;

export class LaserPanel extends HTMLElement {
  #built = false;
  #canvas;
  #nearest;
  #count;
  #tableBody;
  #messageLine;
  #laser = null;
  #scan = null;
  #frame = 0;

  connectedCallback() {
    this.#build();
  }

  set info(info) {
    this.#build();
    this.#laser = info?.laser && typeof info.laser === "object" ? info.laser : null;
    this.#schedule();
  }

  set telemetry(message) {
    const scan = message?.laser;
    if (!scan || !Array.isArray(scan.ranges_m)) return;
    this.#scan = scan;
    this.#schedule();
  }

  set message(message) {
    this.#build();
    this.#messageLine.textContent = message?.message ?? "";
    this.#messageLine.hidden = !message?.message;
  }

  #build() {
    if (this.#built) return;
    this.#built = true;
    this.classList.add("panel", "polar");
    this.#canvas = h("canvas", { class: "polar__canvas", width: 260, height: 260, role: "img",
      "aria-label": "Laser scan around the robot, forward up", "aria-describedby": "laser-nearest-line" });
    this.#nearest = h("span", { "data-field": "laser-nearest", text: "—" });
    this.#count = h("span", { "data-field": "laser-hits", text: "—" });
    this.#tableBody = h("tbody");
    this.#messageLine = h("p", { class: "polar__message", hidden: true });
    this.append(
      h("h2", { class: "panel__title", text: "Laser" }),
      this.#canvas,
      h("p", { class: "polar__summary", id: "laser-nearest-line" }, "Nearest hit: ", this.#nearest, " · ", this.#count,
        " beams hit something"),
      h("details", { class: "polar__details" }, h("summary", { text: "Nearest hit by sector" }),
        h("table", { class: "polar__table" },
          h("caption", { class: "visually-hidden", text: "Nearest laser hit per sector" }),
          h("thead", {}, h("tr", {}, h("th", { scope: "col", text: "Sector" }), h("th", { scope: "col", text: "Range (m)" }))),
          this.#tableBody)),
      this.#messageLine,
    );
  }

  #schedule() {
    if (this.#frame) return;
    this.#frame = requestAnimationFrame(() => {
      this.#frame = 0;
      this.#render();
    });
  }

  #render() {
    if (!this.#scan) return;
    const ranges = this.#scan.ranges_m.map(Number);
    const bearings = laserBearings(this.#scan);
    const maxRange = Number(this.#laser?.max_range_m) || Math.max(1, ...ranges.filter(Number.isFinite));
    const nearest = nearestReading(ranges, bearings, maxRange);
    this.#nearest.textContent = nearest ? `${nearest.range_m.toFixed(2)} m, ${describeBearing(nearest.bearing_rad)}` : "nothing in range";
    this.dataset.nearestM = nearest ? nearest.range_m.toFixed(3) : "";
    this.#count.textContent = String(ranges.filter((r) => isEcho(r, maxRange)).length);
    const sectors = sectorMinima(ranges, bearings, SECTORS, maxRange);
    if (this.#tableBody.children.length !== sectors.length) {
      this.#tableBody.replaceChildren(...sectors.map((sector) => h("tr", {},
        h("th", { scope: "row", text: `${describeBearing(sector.from_rad)} to ${describeBearing(sector.to_rad)}` }),
        h("td", { text: "—" }))));
    }
    sectors.forEach((sector, index) => {
      this.#tableBody.children[index].lastElementChild.textContent = sector.range_m === null ? "nothing" : sector.range_m.toFixed(2);
    });
    this.#draw(ranges, bearings, maxRange);
  }

  #draw(ranges, bearings, maxRange) {
    const canvas = this.#canvas;
    const size = Math.round((canvas.clientWidth || 260) * (window.devicePixelRatio || 1));
    if (canvas.width !== size) { canvas.width = size; canvas.height = size; }
    const ctx = canvas.getContext("2d");
    const c = size / 2;
    const scale = (size / 2 - 6) / maxRange;
    ctx.clearRect(0, 0, size, size);
    ctx.strokeStyle = "#d3d9e1";
    ctx.lineWidth = 1;
    const ringStep = maxRange > 4 ? 1 : 0.5;
    for (let r = ringStep; r <= maxRange; r += ringStep) { ctx.beginPath(); ctx.arc(c, c, r * scale, 0, 2 * Math.PI); ctx.stroke(); }
    // The scanned area, then the hits.
    ctx.fillStyle = "rgb(29 95 196 / 10%)";
    ctx.beginPath();
    ctx.moveTo(c, c);
    ranges.forEach((range, index) => ctx.lineTo(...polarToScreen(c, c, scale, Number.isFinite(range) ? Math.min(range, maxRange) : maxRange, bearings[index])));
    ctx.closePath();
    ctx.fill();
    ctx.fillStyle = "#d1390f";
    const dot = Math.max(2, size / 130);
    ranges.forEach((range, index) => {
      if (!isEcho(range, maxRange)) return;
      const [x, y] = polarToScreen(c, c, scale, range, bearings[index]);
      ctx.fillRect(x - dot / 2, y - dot / 2, dot, dot);
    });
    ctx.fillStyle = "#1d5fc4";
    ctx.beginPath();
    ctx.moveTo(c, c - 10); ctx.lineTo(c - 7, c + 7); ctx.lineTo(c + 7, c + 7);
    ctx.fill();
  }
}

export function register() {
  adoptStylesheet(new URL("../sonar-panel/sonar-panel.css", import.meta.url));
  adoptStylesheet(new URL("./laser-panel.css", import.meta.url));
  defineOnce("laser-panel", LaserPanel);
}
