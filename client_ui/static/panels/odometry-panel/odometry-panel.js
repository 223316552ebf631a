// <odometry-panel>: the robot's pose and speeds as the telemetry socket reports them.
// In: `telemetry` (a {"type": "telemetry", ...} message), `message` (status/error JSON).
// Out: none. Each number sits alone in a [data-field] element so tests and people can read it. When the odometry is
// far off where the robot stands (the telemetry's camera_pose; none in a graded run), a note says so and names the
// ways back, since skills and plans steer by these numbers.
// A small time plot shows the last 30 s of speed and turn rate (redrawn at most 5 times a second).

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed, t } from "../../lib/i18n.js";

const DEG_PER_RAD = 180 / Math.PI;
const PLOT_WINDOW_S = 30;
const PLOT_REDRAW_MS = 200;
const DRIFT_NOTED_M = 0.3;

/** The sentence for odometry further than DRIFT_NOTED_M from where the robot stands, else ""; pure. */
export function driftNote(message) {
  const odometry = message?.odometry?.pose;
  const standing = message?.camera_pose;
  if (!odometry || !standing) return "";
  const off_m = Math.hypot(odometry.x_m - standing.x_m, odometry.y_m - standing.y_m);
  if (!(off_m >= DRIFT_NOTED_M)) return "";
  return t("These numbers are {off_m} m off where the robot stands (the camera shows it there), and ", { off_m: fixed(off_m, 1) })
    + t("skills and plans steer by them. Localize it (Navigate tab: Localization) or return it to its dock (Navigate tab: the map's \"Return to the dock\").");
}

/** Samples of the last windowS seconds before nowS; pure. */
export function trimHistory(samples, nowS, windowS = PLOT_WINDOW_S) {
  return samples.filter((sample) => nowS - sample.t_s <= windowS);
}

/** How long ago the robot last applied a drive command, as a person reads it; the sequence number itself (wall-clock
 *  milliseconds on the wire, so that it survives a worker change) means nothing to them. Pure. */
export function appliedAgo(appliedAtMs, nowMs) {
  if (!Number.isFinite(appliedAtMs)) return t("none since this panel opened");
  const ago_s = Math.max(0, (nowMs - appliedAtMs) / 1000);
  if (ago_s < 1) return t("just now");
  if (ago_s < 60) return t("{ago_s} s ago", { ago_s: Math.floor(ago_s) });
  if (ago_s < 3600) return t("{value} min ago", { value: Math.floor(ago_s / 60) });
  return t("{value} h ago", { value: Math.floor(ago_s / 3600) });
}

/** Format a finite number with fixed decimals; "—" for anything else. Avoids printing "-0.00". */
export function formatNumber(value, decimals) {
  const number = Number(value);
  if (value === null || value === undefined || !Number.isFinite(number)) return "—";
  const rounded = Number(number.toFixed(decimals)); // data, not text: rounds first, so -0.001 reads 0.00
  return fixed(rounded, decimals);
}

/** Heading in degrees, wrapped to (-180, 180]. */
export function headingDegrees(thetaRad) {
  let degrees = Number(thetaRad) * DEG_PER_RAD;
  degrees = ((((degrees + 180) % 360) + 360) % 360) - 180;
  return degrees === -180 ? 180 : degrees;
}

const ROWS = [
  { label: "x", field: "x", unit: "m" },
  { label: "y", field: "y", unit: "m" },
  { label: t("Heading"), field: "heading", unit: "°", extra: { field: "heading-rad", unit: "rad" } },
  { label: t("Speed"), field: "linear", unit: "m/s" },
  { label: t("Turn rate"), field: "angular", unit: "rad/s", extra: { field: "angular-deg", unit: "°/s" } },
];

export class OdometryPanel extends PanelElement {
  #fields = new Map();
  #deadmanNote;
  #driftNote;
  #plot;
  #history = [];
  #plotTimer = 0;
  #limits = { max_linear_mps: 0.5, max_angular_radps: 1.5 };
  #appliedSequence;             // the last applied sequence seen (undefined before the first message)
  #appliedAtMs = NaN;           // when it changed, by performance.now()

  connectedCallback() {
    super.connectedCallback();
    clearInterval(this.#plotTimer);
    this.#plotTimer = setInterval(() => { this.#drawPlot(); this.#showApplied(); }, PLOT_REDRAW_MS);
  }

  disconnectedCallback() {
    super.disconnectedCallback();
    clearInterval(this.#plotTimer);
  }

  /** The robot's limits set the plot's scales. */
  set limits(limits) {
    if (limits?.max_linear_mps > 0 && limits?.max_angular_radps > 0) this.#limits = limits;
  }

  build() {
    this.classList.add("panel");
    const field = (name) => {
      const element = h("span", { class: "odometry__value", "data-field": name, text: "—" });
      this.#fields.set(name, element);
      return element;
    };
    const list = h("dl", { class: "odometry__list" },
      ROWS.map((row) => h("div", { class: "odometry__row" },
        h("dt", { text: row.label }),
        h("dd", {},
          field(row.field), h("span", { class: "odometry__unit", text: row.unit }),
          row.extra && h("span", { class: "odometry__extra" },
            field(row.extra.field), h("span", { class: "odometry__unit", text: row.extra.unit }))))));
    this.#deadmanNote = h("p", {
      class: "odometry__note", "data-field": "deadman", hidden: true,
      text: t("Stopped by the safety deadman: no drive commands arrived in time."),
    });
    this.#driftNote = h("p", { class: "odometry__note", "data-field": "drift", hidden: true });
    this.append(
      h("h2", { class: "panel__title", text: t("Odometry") }),
      list,
      this.#deadmanNote,
      this.#driftNote,
      this.messageLine({ class: "odometry__message", "data-field": "telemetry-message" }),
      h("figure", { class: "odometry__plot" },
        this.#plot = h("canvas", { width: 320, height: 110, role: "img", "data-field": "odometry-plot",
          "aria-label": t("Speed and turn rate over the last 30 seconds") }),
        h("figcaption", {},
          h("span", { class: "odometry__key odometry__key--speed", text: t("speed (m/s)") }),
          h("span", { class: "odometry__key odometry__key--turn", text: t("turn rate (rad/s)") }),
          h("span", { class: "muted", text: t(" · last 30 s") }))),
      h("p", { class: "odometry__meta" },
        t("tick "), field("tick"), t(" · last command applied "), field("last-applied")),
    );
  }

  /** A telemetry message from the server. */
  set telemetry(message) {
    this.ensureBuilt();
    const odometry = message?.odometry ?? {};
    const pose = odometry.pose ?? {};
    const set = (name, text) => { this.#fields.get(name).textContent = text; };
    set("x", formatNumber(pose.x_m, 2));
    set("y", formatNumber(pose.y_m, 2));
    set("heading", Number.isFinite(Number(pose.theta_rad)) && pose.theta_rad !== null
      ? formatNumber(headingDegrees(pose.theta_rad), 0) : "—");
    set("heading-rad", formatNumber(pose.theta_rad, 2));
    set("linear", formatNumber(odometry.linear_mps, 2));
    set("angular", formatNumber(odometry.angular_radps, 2));
    set("angular-deg", formatNumber(Number(odometry.angular_radps) * DEG_PER_RAD, 0));
    set("tick", formatNumber(message?.tick, 0));
    this.#noteApplied(message?.last_applied_sequence);
    this.#deadmanNote.hidden = message?.deadman_stopped !== true;
    const drift = driftNote(message);
    if (this.#driftNote.textContent !== drift) this.#driftNote.textContent = drift;
    this.#driftNote.hidden = !drift;
    const linear = Number(odometry.linear_mps);
    const angular = Number(odometry.angular_radps);
    if (Number.isFinite(linear) && Number.isFinite(angular)) {
      const t_s = performance.now() / 1000;
      this.#history.push({ t_s, linear, angular });
      if (this.#history.length > 2000) this.#history = trimHistory(this.#history, t_s);
    }
    this.showMessage("");
  }

  #noteApplied(sequence) {
    if (!Number.isFinite(Number(sequence)) || sequence === null) return;
    if (this.#appliedSequence !== undefined && sequence !== this.#appliedSequence) this.#appliedAtMs = performance.now();
    this.#appliedSequence = sequence;
    this.#showApplied();
  }

  #showApplied() {
    const field = this.#fields.get("last-applied");
    const text = appliedAgo(this.#appliedAtMs, performance.now());
    if (field && field.textContent !== text) field.textContent = text;
  }

  #drawPlot() {
    const canvas = this.#plot;
    if (!canvas || !this.isConnected || !canvas.offsetParent) return;
    const nowS = performance.now() / 1000;
    this.#history = trimHistory(this.#history, nowS);
    const width = Math.max(120, Math.round(canvas.clientWidth * (window.devicePixelRatio || 1)));
    const height = Math.round(width * 0.34);
    if (canvas.width !== width || canvas.height !== height) {
      canvas.width = width;
      canvas.height = height;
    }
    const ctx = canvas.getContext("2d");
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, width, height);
    ctx.strokeStyle = "#d3d9e1";
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.moveTo(0, height / 2);
    ctx.lineTo(width, height / 2);
    ctx.stroke();
    const x = (t_s) => width - ((nowS - t_s) / PLOT_WINDOW_S) * width;
    const series = [
      ["linear", this.#limits.max_linear_mps, "#1d5fc4"],
      ["angular", this.#limits.max_angular_radps, "#b1261b"],
    ];
    ctx.lineWidth = Math.max(1.5, width / 240);
    for (const [key, limit, colour] of series) {
      ctx.strokeStyle = colour;
      ctx.beginPath();
      this.#history.forEach((sample, index) => {
        const y = height / 2 - (Math.max(-1, Math.min(1, sample[key] / limit)) * (height / 2 - 3));
        if (index === 0) ctx.moveTo(x(sample.t_s), y);
        else ctx.lineTo(x(sample.t_s), y);
      });
      ctx.stroke();
    }
  }

  /** A text status/error message from the telemetry socket. */
  set message(message) {
    this.showMessage(message?.message || (message?.type === "status" && !message.robot_online ? t("The robot is offline.") : ""));
  }
}

export const register = registerPanel({
  kind: "odometry", tag: "odometry-panel", element: OdometryPanel,
  stylesheets: [new URL("./odometry-panel.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "message", error: "message" } },
    { robotInfo: "limits", fields: ["max_linear_mps", "max_angular_radps"] },
  ],
});
