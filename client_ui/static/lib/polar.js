// Pure geometry of the polar sensor views (sonar, laser): forward is up on screen, left is left.

import { t } from "./i18n.js";

/** Screen point for a reading at range_m and bearing_rad (0 = forward, + = left), around (cx, cy). */
export function polarToScreen(cx, cy, scale_px_per_m, range_m, bearing_rad) {
  return [cx - Math.sin(bearing_rad) * range_m * scale_px_per_m, cy - Math.cos(bearing_rad) * range_m * scale_px_per_m];
}

/** The bearing of every laser beam. */
export function laserBearings(scan) {
  const start = Number(scan?.angle_min_rad);
  const step = Number(scan?.angle_increment_rad);
  const count = Array.isArray(scan?.ranges_m) ? scan.ranges_m.length : 0;
  if (!Number.isFinite(start) || !Number.isFinite(step)) return [];
  return Array.from({ length: count }, (_, index) => start + index * step);
}

/** A valid echo: finite, positive and short of the sensor's maximum (which means "nothing seen"). */
export function isEcho(range_m, maxRange_m = Infinity) {
  return Number.isFinite(range_m) && range_m > 0 && range_m < maxRange_m - 1e-3;
}

/** The nearest valid reading: {index, range_m, bearing_rad} or null. */
export function nearestReading(ranges, bearings, maxRange_m = Infinity) {
  let best = null;
  (ranges ?? []).forEach((range, index) => {
    const bearing = bearings[index];
    if (!isEcho(range, maxRange_m) || !Number.isFinite(bearing)) return;
    if (!best || range < best.range_m) best = { index, range_m: range, bearing_rad: bearing };
  });
  return best;
}

/** Words for a bearing: "ahead", "12° left", "40° right", "behind". */
export function describeBearing(bearing_rad) {
  let degrees = (bearing_rad * 180) / Math.PI;
  degrees = ((((degrees + 180) % 360) + 360) % 360) - 180;
  const rounded = Math.round(Math.abs(degrees));
  if (rounded <= 2) return t("ahead");
  if (rounded >= 178) return t("behind");
  return degrees > 0 ? t("{degrees}° left", { degrees: rounded }) : t("{degrees}° right", { degrees: rounded });
}

/** The nearest echo in each of `count` equal sectors spanning the bearings given, for a readable summary. */
export function sectorMinima(ranges, bearings, count, maxRange_m = Infinity) {
  if (!bearings.length) return [];
  const low = Math.min(...bearings);
  const high = Math.max(...bearings);
  const width = (high - low) / count || 1;
  const sectors = Array.from({ length: count }, (_, i) => ({ from_rad: low + i * width, to_rad: low + (i + 1) * width,
    range_m: null }));
  ranges.forEach((range, index) => {
    if (!isEcho(range, maxRange_m)) return;
    const sector = sectors[Math.min(count - 1, Math.floor((bearings[index] - low) / width))];
    if (sector.range_m === null || range < sector.range_m) sector.range_m = range;
  });
  return sectors;
}
