// A student's response times in the tutor's class view: the figures their console's panel shows (reported by
// lib/console/timing-report.js), totals on the row and each leg in a table under "Legs".

import { h } from "../../lib/dom.js";
import { KINDS, LEGS, reportLine } from "../../lib/response-times.js";
import { fixed, t } from "../../lib/i18n.js";

const LEG_LABELS = { total: t("Total"), client: t("Browser → middleware"), robot: t("Middleware → robot") };
const FIGURES = [["min", t("Min")], ["mean", t("Mean")], ["max", t("Max")], ["jitter", t("Jitter (IQR)")]];

function ms(value) {
  return Number.isFinite(value) ? fixed(value, 1) : "—";
}

function legsTable(report) {
  return h("table", { class: "class-rtt__legs" },
    h("thead", {}, h("tr", {}, h("th", { scope: "col", text: t("Round trip (ms)") }),
      FIGURES.map(([, label]) => h("th", { scope: "col", text: label })))),
    h("tbody", {}, KINDS.filter((kind) => report[kind]?.count).flatMap((kind) => LEGS.map((leg) => h("tr", {},
      h("th", { scope: "row", text: `${kind === "skill" ? t("Skills") : t("Drive")}: ${LEG_LABELS[leg]}` }),
      FIGURES.map(([figure]) => h("td", { "data-field": `rtt-${kind}-${leg}-${figure}`,
        text: ms(report[kind][leg][figure]) })))))));
}

/** The content of a seat's "Response times" cell. */
export function responseTimesCell(report) {
  if (!report) return [h("span", { class: "muted", text: t("not measured yet") })];
  const { late, lost } = report.delivery;
  return [
    ...KINDS.map((kind) => h("div", { "data-field": `rtt-${kind}-line`, text: reportLine(report, kind) })),
    h("div", { "data-field": "rtt-delivery", text: t("{late} late, {lost} lost", { late, lost }) }),
    h("details", {}, h("summary", { text: t("Legs") }), legsTable(report)),
  ];
}
