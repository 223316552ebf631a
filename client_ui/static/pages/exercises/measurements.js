// A rubric's measurements as the grade table shows them: the value and the bar with their unit, in the page's language
// (decimal sign, a count of cells agreeing with its noun). Pure, so it is tested in node.
import { fixed, isSingular, number, t } from "../../lib/i18n.js";

const CELLS = "cells";  // the one unit that is a word (grading.py's CELLS)

/** A count of floor cells in words: "1 cell", "14 cells" ("1 casilla", "14 casillas"). */
export function cellsText(count) {
  return isSingular(count) ? t("{count} cell", { count: number(count) }) : t("{count} cells", { count: number(count) });
}

/** A measured value: a whole count of cells, else 2 decimals (1 from 10 up), "—" when it is not a number. */
export function valueText(value, unit = "") {
  if (unit === CELLS) return cellsText(Math.round(value));
  const shown = Number.isFinite(value) ? fixed(value, Math.abs(value) >= 10 ? 1 : 2) : "—";
  return unit ? `${shown} ${unit}` : shown;
}

/** The table's cells for one measurement: [name, value, bar, points]. */
export function measurementRow(m) {
  const bar = m.unit === CELLS ? cellsText(m.bar) : `${number(m.bar)}${m.unit ? ` ${m.unit}` : ""}`;
  return [m.name, valueText(m.value, m.unit), `${m.lower_is_better ? "≤" : "≥"} ${bar}`, `${Math.round(m.fraction * 100)}%`];
}
