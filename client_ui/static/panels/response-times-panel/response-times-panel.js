// <response-times-panel>: the 2003 paper's table 1, measured on this console's own commands. Every skill activation
// and every drive command is timed over its two legs: browser -> middleware (the whole round trip less the robot's
// part) and middleware -> skill server (the middleware's call to the robot, which it reports in its answer). Each
// leg shows minimum, mean, maximum and jitter (the inter-quartile range, as the paper takes it); below, the
// connection's throughput and its late and lost commands (the paper's bandwidth and packet-loss study).
// In: `report` ({log: a TimingLog of lib/response-times.js, nowMs}). Out: none. `samples` gives the timed commands.

import { h } from "../../lib/dom.js";
import { LATE_AFTER_MS, LEGS } from "../../lib/response-times.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

const KIND_TITLES = { skill: t("Skill activations"), drive: t("Drive commands") };
const LEG_LABELS = { total: t("Total"), client: t("Browser → middleware"), robot: t("Middleware → robot") };
const FIGURES = [["min", t("Min")], ["mean", t("Mean")], ["max", t("Max")], ["jitter", t("Jitter (IQR)")]];
const THROUGHPUT_WINDOW_MS = 10000;

/** Milliseconds with one decimal, "—" for none. */
export function formatMs(value) {
  return Number.isFinite(value) ? fixed(value, 1) : "—";
}

/** Bytes per second as a person reads them. */
export function formatRate(bytesPerS) {
  if (!Number.isFinite(bytesPerS)) return "—";
  return bytesPerS >= 1000 ? t("{value} kB/s", { value: fixed(bytesPerS / 1000, 1) }) : `${Math.round(bytesPerS)} B/s`;
}

export class ResponseTimesPanel extends PanelElement {
  #cells = new Map();
  #log = null;
  #nowMs = 0;

  /** The console's timing log, read at nowMs. */
  set report({ log, nowMs }) {
    this.ensureBuilt();
    this.#log = log;
    this.#nowMs = nowMs;
    this.scheduleRender();
  }

  /** The timed commands, {skill: [...], drive: [...]}, each {total_ms, client_ms, robot_ms, at_ms}. */
  get samples() {
    return { skill: this.#log?.samples("skill") ?? [], drive: this.#log?.samples("drive") ?? [] };
  }

  #cell(field) {
    const element = h("td", { "data-field": field, text: "—" });
    this.#cells.set(field, element);
    return element;
  }

  #value(field) {
    const element = h("span", { "data-field": field, text: "—" });
    this.#cells.set(field, element);
    return element;
  }

  build() {
    this.classList.add("panel", "rtt");
    const table = (kind) => h("table", { class: "rtt__table", "data-kind": kind },
      h("caption", {}, `${KIND_TITLES[kind]} · `, this.#value(`rtt-${kind}-count`), t(" timed (ms)")),
      h("thead", {}, h("tr", {}, h("th", { scope: "col", text: t("Round trip") }),
        FIGURES.map(([, label]) => h("th", { scope: "col", text: label })))),
      h("tbody", {}, LEGS.map((leg) => h("tr", {},
        h("th", { scope: "row", text: LEG_LABELS[leg] }),
        FIGURES.map(([figure]) => this.#cell(`rtt-${kind}-${leg}-${figure}`))))));
    this.append(
      h("h2", { class: "panel__title", text: t("Response times") }),
      table("skill"),
      table("drive"),
      h("p", { class: "rtt__connection", "data-field": "rtt-connection" },
        t("Throughput "), this.#value("rtt-throughput"), " · ", this.#value("rtt-sent"), t(" sent · "),
        this.#value("rtt-late"), t(" late (over {value} s) · ", { value: LATE_AFTER_MS / 1000 }), this.#value("rtt-lost"), t(" lost")),
      h("p", { class: "rtt__help muted", text: t("Timed on your own skill activations and drive commands since this console opened. Browser → middleware is the whole round trip less the middleware's call to the robot; jitter is the spread of the middle half of the round trips.") }),
    );
  }

  render() {
    const log = this.#log;
    if (!log) return;
    const set = (field, text) => {
      const element = this.#cells.get(field);
      if (element.textContent !== text) element.textContent = text;
    };
    for (const kind of Object.keys(KIND_TITLES)) {
      const figures = log.figures(kind);
      set(`rtt-${kind}-count`, String(figures.total.count));
      for (const leg of LEGS) for (const [figure] of FIGURES) set(`rtt-${kind}-${leg}-${figure}`, formatMs(figures[leg][figure]));
    }
    const delivery = log.delivery();
    set("rtt-throughput", formatRate(log.throughput(this.#nowMs, THROUGHPUT_WINDOW_MS)));
    set("rtt-sent", String(delivery.sent));
    set("rtt-late", String(delivery.late));
    set("rtt-lost", String(delivery.lost));
  }
}

export const register = registerPanel({
  kind: "response-times", tag: "response-times-panel", element: ResponseTimesPanel,
  stylesheets: [new URL("./response-times-panel.css", import.meta.url)],
  feeds: [{ service: "response-times" }],
});
