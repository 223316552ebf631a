// <sonar-panel>: a polar view of the sonar ring (forward is up), with the nearest echo in words and
// every reading in a table. In: `info` (robot info with `sonars`), `telemetry`, `message`. Out: none.

import { h } from "../../lib/dom.js";
import { describeBearing, isEcho, nearestReading, polarToScreen } from "../../lib/polar.js";
import { POLAR_STYLESHEET, PolarPanel } from "../polar-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

export class SonarPanel extends PolarPanel {
  #nearest;
  #sonars = [];
  #ranges = [];

  polarView() {
    this.#nearest = h("span", { "data-field": "sonar-nearest", text: "—" });
    return {
      title: t("Sonar"), canvasLabel: t("Sonar readings around the robot, forward up"),
      summaryId: "sonar-nearest-line", summaryAttrs: { "aria-live": "off" }, summary: [t("Nearest echo: "), this.#nearest],
      details: t("All sonar readings"), caption: t("Sonar readings"), columns: [t("Sonar"), t("Bearing"), t("Range (m)")],
    };
  }

  set info(info) {
    this.ensureBuilt();
    this.#sonars = Array.isArray(info?.sonars) ? info.sonars : [];
    this.readingsBody.replaceChildren(...this.#sonars.map((sonar, index) => h("tr", {},
      h("th", { scope: "row", text: String(index + 1) }),
      h("td", { text: describeBearing(Number(sonar.mount_angle_rad)) }),
      h("td", { "data-sonar-range": String(index), text: "—" }))));
    this.scheduleRender();
  }

  set telemetry(message) {
    const ranges = message?.sonar?.ranges_m;
    if (!Array.isArray(ranges)) return;
    this.#ranges = ranges.map(Number);
    this.scheduleRender();
  }

  render() {
    const bearings = this.#sonars.map((s) => Number(s.mount_angle_rad));
    const maxRange = Math.max(0.5, ...this.#sonars.map((s) => Number(s.max_range_m) || 0));
    const nearest = nearestReading(this.#ranges, bearings, maxRange);
    this.showNearest(this.#nearest, nearest, nearest
      ? t("{range_m} m, {bearing_rad} (sonar {value})", { range_m: fixed(nearest.range_m, 2), bearing_rad: describeBearing(nearest.bearing_rad), value: nearest.index + 1 })
      : this.#ranges.length ? t("nothing in range") : "—");
    this.readingsBody.querySelectorAll("[data-sonar-range]").forEach((cell, index) => {
      const range = this.#ranges[index];
      cell.textContent = isEcho(range, Number(this.#sonars[index]?.max_range_m) || Infinity) ? fixed(range, 2) : t("no echo");
    });
    this.drawPolar(maxRange, 0.5, (ctx, c, scale) => this.#drawCones(ctx, c, scale, maxRange));
  }

  #drawCones(ctx, c, scale, maxRange) {
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
  }
}

export const register = registerPanel({
  kind: "sonar", tag: "sonar-panel", element: SonarPanel, stylesheets: [POLAR_STYLESHEET],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "message", error: "message" } },
    { robotInfo: "info" },
  ],
});
