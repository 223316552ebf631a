// <odometry-panel>: the robot's pose and speeds as the telemetry socket reports them.
// In: `telemetry` (a {"type": "telemetry", ...} message), `message` (status/error JSON).
// Out: none. Each number sits alone in a [data-field] element so tests and people can read it.

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";

const DEG_PER_RAD = 180 / Math.PI;

/** Format a finite number with fixed decimals; "—" for anything else. Avoids printing "-0.00". */
export function formatNumber(value, decimals) {
  const number = Number(value);
  if (value === null || value === undefined || !Number.isFinite(number)) return "—";
  const text = number.toFixed(decimals);
  return Number(text) === 0 ? (0).toFixed(decimals) : text;
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
  { label: "Heading", field: "heading", unit: "°", extra: { field: "heading-rad", unit: "rad" } },
  { label: "Speed", field: "linear", unit: "m/s" },
  { label: "Turn rate", field: "angular", unit: "rad/s", extra: { field: "angular-deg", unit: "°/s" } },
];

export class OdometryPanel extends HTMLElement {
  #fields = new Map();
  #deadmanNote;
  #messageLine;
  #built = false;

  connectedCallback() {
    this.#build();
  }

  #build() {
    if (this.#built) return;
    this.#built = true;
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
      text: "Stopped by the safety deadman: no drive commands arrived in time.",
    });
    this.#messageLine = h("p", { class: "odometry__message", "data-field": "telemetry-message", hidden: true });
    this.append(
      h("h2", { class: "panel__title", text: "Odometry" }),
      list,
      this.#deadmanNote,
      this.#messageLine,
      h("p", { class: "odometry__meta" },
        "tick ", field("tick"), " · last applied command ", field("last-applied")),
    );
  }

  /** A telemetry message from the server. */
  set telemetry(message) {
    this.#build();
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
    set("last-applied", formatNumber(message?.last_applied_sequence, 0));
    this.#deadmanNote.hidden = message?.deadman_stopped !== true;
    this.#messageLine.hidden = true;
  }

  /** A text status/error message from the telemetry socket. */
  set message(message) {
    this.#build();
    const text = message?.message || (message?.type === "status" && !message.robot_online ? "The robot is offline." : "");
    this.#messageLine.textContent = text;
    this.#messageLine.hidden = !text;
  }
}

export function register() {
  adoptStylesheet(new URL("./odometry-panel.css", import.meta.url));
  defineOnce("odometry-panel", OdometryPanel);
}
