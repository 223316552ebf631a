// <laser-panel>: a polar view of the laser scan (forward is up), with the nearest hit in words and the
// nearest hit per sector in a table. In: `info` (robot info with `laser`), `telemetry`, `message`. Out: none.

import { h } from "../../lib/dom.js";
import { describeBearing, isEcho, laserBearings, nearestReading, polarToScreen, sectorMinima } from "../../lib/polar.js";
import { POLAR_STYLESHEET, PolarPanel } from "../polar-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

const SECTORS = 8;

export class LaserPanel extends PolarPanel {
  #nearest;
  #count;
  #laser = null;
  #scan = null;

  polarView() {
    this.#nearest = h("span", { "data-field": "laser-nearest", text: "—" });
    this.#count = h("span", { "data-field": "laser-hits", text: "—" });
    return {
      title: t("Laser"), canvasLabel: t("Laser scan around the robot, forward up"), summaryId: "laser-nearest-line",
      summary: [t("Nearest hit: "), this.#nearest, " · ", this.#count, t(" beams hit something")],
      details: t("Nearest hit by sector"), caption: t("Nearest laser hit per sector"), columns: [t("Sector"), t("Range (m)")],
    };
  }

  set info(info) {
    this.ensureBuilt();
    this.#laser = info?.laser && typeof info.laser === "object" ? info.laser : null;
    this.scheduleRender();
  }

  set telemetry(message) {
    const scan = message?.laser;
    if (!scan || !Array.isArray(scan.ranges_m)) return;
    this.#scan = scan;
    this.scheduleRender();
  }

  render() {
    if (!this.#scan) return;
    const ranges = this.#scan.ranges_m.map(Number);
    const bearings = laserBearings(this.#scan);
    const maxRange = Number(this.#laser?.max_range_m) || Math.max(1, ...ranges.filter(Number.isFinite));
    const nearest = nearestReading(ranges, bearings, maxRange);
    this.showNearest(this.#nearest, nearest,
      nearest ? `${fixed(nearest.range_m, 2)} m, ${describeBearing(nearest.bearing_rad)}` : t("nothing in range"));
    this.#count.textContent = String(ranges.filter((r) => isEcho(r, maxRange)).length);
    const body = this.readingsBody;
    const sectors = sectorMinima(ranges, bearings, SECTORS, maxRange);
    if (body.children.length !== sectors.length) {
      body.replaceChildren(...sectors.map((sector) => h("tr", {},
        h("th", { scope: "row", text: t("{from_rad} to {to_rad}", { from_rad: describeBearing(sector.from_rad), to_rad: describeBearing(sector.to_rad) }) }),
        h("td", { text: "—" }))));
    }
    sectors.forEach((sector, index) => {
      body.children[index].lastElementChild.textContent = sector.range_m === null ? t("nothing") : fixed(sector.range_m, 2);
    });
    this.drawPolar(maxRange, maxRange > 4 ? 1 : 0.5, (ctx, c, scale, size) => {
      // The scanned area, then the hits.
      ctx.fillStyle = "rgb(29 95 196 / 10%)";
      ctx.beginPath();
      ctx.moveTo(c, c);
      ranges.forEach((range, index) => ctx.lineTo(...polarToScreen(c, c, scale,
        Number.isFinite(range) ? Math.min(range, maxRange) : maxRange, bearings[index])));
      ctx.closePath();
      ctx.fill();
      ctx.fillStyle = "#d1390f";
      const dot = Math.max(2, size / 130);
      ranges.forEach((range, index) => {
        if (!isEcho(range, maxRange)) return;
        const [x, y] = polarToScreen(c, c, scale, range, bearings[index]);
        ctx.fillRect(x - dot / 2, y - dot / 2, dot, dot);
      });
    });
  }
}

export const register = registerPanel({
  kind: "laser", tag: "laser-panel", element: LaserPanel, stylesheets: [POLAR_STYLESHEET],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "message", error: "message" } },
    { robotInfo: "info" },
  ],
});
