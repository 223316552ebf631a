// <sonar-panel>: a polar view of the sonar ring (forward is up), with the nearest echo in words and
// every reading in a table. In: `info` (robot info with `sonars`), `telemetry`, `message`. Out: none.

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";
import { describeBearing, isEcho, nearestReading, polarToScreen } from "../../js/polar.js";

const DEG_PER_RAD = 180 / Math.PI;

export class SonarPanel extends HTMLElement {
  #built = false;
  #canvas;
  #nearest;
  #tableBody;
  #messageLine;
  #sonars = [];
  #ranges = [];
  #frame = 0;

  connectedCallback() {
    this.#build();
  }

  set info(info) {
    this.#build();
    this.#sonars = Array.isArray(info?.sonars) ? info.sonars : [];
    this.#rebuildTable();
    this.#schedule();
  }

  set telemetry(message) {
    const ranges = message?.sonar?.ranges_m;
    if (!Array.isArray(ranges)) return;
    this.#ranges = ranges.map(Number);
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
      "aria-label": "Sonar readings around the robot, forward up", "aria-describedby": "sonar-nearest-line" });
    this.#nearest = h("span", { "data-field": "sonar-nearest", text: "—" });
    this.#tableBody = h("tbody");
    this.#messageLine = h("p", { class: "polar__message", hidden: true });
    this.append(
      h("h2", { class: "panel__title", text: "Sonar" }),
      this.#canvas,
      h("p", { class: "polar__summary", id: "sonar-nearest-line", "aria-live": "off" }, "Nearest echo: ", this.#nearest),
      h("details", { class: "polar__details" }, h("summary", { text: "All sonar readings" }),
        h("table", { class: "polar__table" },
          h("caption", { class: "visually-hidden", text: "Sonar readings" }),
          h("thead", {}, h("tr", {}, h("th", { scope: "col", text: "Sonar" }), h("th", { scope: "col", text: "Bearing" }),
            h("th", { scope: "col", text: "Range (m)" }))),
          this.#tableBody)),
      this.#messageLine,
    );
  }

  #rebuildTable() {
    this.#tableBody.replaceChildren(...this.#sonars.map((sonar, index) => h("tr", {},
      h("th", { scope: "row", text: String(index + 1) }),
      h("td", { text: describeBearing(Number(sonar.mount_angle_rad)) }),
      h("td", { "data-sonar-range": String(index), text: "—" }))));
  }

  #schedule() {
    if (this.#frame) return;
    this.#frame = requestAnimationFrame(() => {
      this.#frame = 0;
      this.#render();
    });
  }

  #render() {
    const bearings = this.#sonars.map((s) => Number(s.mount_angle_rad));
    const maxRange = Math.max(0.5, ...this.#sonars.map((s) => Number(s.max_range_m) || 0));
    const nearest = nearestReading(this.#ranges, bearings, maxRange);
    this.#nearest.textContent = nearest
      ? `${nearest.range_m.toFixed(2)} m, ${describeBearing(nearest.bearing_rad)} (sonar ${nearest.index + 1})`
      : this.#ranges.length ? "nothing in range" : "—";
    this.dataset.nearestM = nearest ? nearest.range_m.toFixed(3) : "";
    this.#tableBody.querySelectorAll("[data-sonar-range]").forEach((cell, index) => {
      const range = this.#ranges[index];
      cell.textContent = isEcho(range, Number(this.#sonars[index]?.max_range_m) || Infinity) ? range.toFixed(2) : "no echo";
    });
    this.#draw(maxRange);
  }

  #draw(maxRange) {
    const canvas = this.#canvas;
    const size = Math.round((canvas.clientWidth || 260) * (window.devicePixelRatio || 1));
    if (canvas.width !== size) { canvas.width = size; canvas.height = size; }
    const ctx = canvas.getContext("2d");
    const c = size / 2;
    const scale = (size / 2 - 6) / maxRange;
    ctx.clearRect(0, 0, size, size);
    ctx.strokeStyle = "#d3d9e1";
    ctx.lineWidth = 1;
    for (let r = 0.5; r <= maxRange; r += 0.5) { ctx.beginPath(); ctx.arc(c, c, r * scale, 0, 2 * Math.PI); ctx.stroke(); }
    this.#sonars.forEach((sonar, index) => {
      const range = this.#ranges[index];
      const echo = isEcho(range, Number(sonar.max_range_m) || Infinity);
      const reach = echo ? range : Number(sonar.max_range_m) || maxRange;
      const half = Number(sonar.cone_half_angle_rad) || 0.13;
      const bearing = Number(sonar.mount_angle_rad);
      ctx.beginPath();
      ctx.moveTo(c, c);
      for (let i = 0; i <= 6; i += 1) ctx.lineTo(...polarToScreen(c, c, scale, reach, bearing - half + (2 * half * i) / 6));
      ctx.closePath();
      ctx.fillStyle = echo ? "rgb(194 106 0 / 35%)" : "rgb(79 91 107 / 8%)";
      ctx.fill();
      if (echo) { ctx.strokeStyle = "#8a5300"; ctx.stroke(); }
    });
    ctx.fillStyle = "#1d5fc4";
    ctx.beginPath();
    ctx.moveTo(c, c - 10); ctx.lineTo(c - 7, c + 7); ctx.lineTo(c + 7, c + 7);
    ctx.fill();
  }
}

export function register() {
  adoptStylesheet(new URL("./sonar-panel.css", import.meta.url));
  defineOnce("sonar-panel", SonarPanel);
}

/** Degrees of a bearing, for tables elsewhere. */
export function bearingDegrees(bearing_rad) {
  return Math.round(bearing_rad * DEG_PER_RAD);
}
