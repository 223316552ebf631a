// <connection-status>: one line per socket (camera, telemetry, drive): connected, reconnecting in
// N s, closed with the reason, or off on purpose (phase "off", e.g. the camera socket while the picture is
// drawn by this browser: calm, not a fault); and a line for the robot itself, since the sockets reach the lab
// server even while the robot behind it does not answer. In: `loginUrl` (string), `robotName` (string),
// `robotOnline` (boolean), and `update(name, state)` with a transport Channel state. Out: none.

import { h } from "../../lib/dom.js";
import { CLOSE_CODES } from "../../lib/transport.js";
import { elementRegistrar, PanelElement } from "../panel-base.js";
import { t } from "../../lib/i18n.js";

const LABELS = { camera: t("Camera"), telemetry: t("Telemetry"), drive: t("Drive"), queue: t("Queue") };

/** A sentence for a channel state; pure so it can be tested. */
export function describeState(state, { robotName = t("the robot"), nowMs = Date.now() } = {}) {
  switch (state?.phase) {
    case "open":
      return t("connected");
    case "connecting":
      return t("connecting…");
    case "reconnecting": {
      const seconds = Math.max(0, Math.ceil((state.retryAt - nowMs) / 1000));
      const why = state.reason ? ` (${state.reason})` : "";
      return seconds > 0 ? t("reconnecting in {seconds} s{why}", { seconds, why }) : t("reconnecting…");
    }
    case "off":
      return state.reason || "off";
    case "closed":
      if (state.code === CLOSE_CODES.NOT_LOGGED_IN) return t("closed: your session has ended");
      if (state.code === CLOSE_CODES.NOT_ALLOWED) return t("closed: you are not allowed to use this robot");
      if (state.code === CLOSE_CODES.UNKNOWN_ROBOT) return t("closed: there is no robot called {robotName}", { robotName });
      return state.reason ? t("closed: {reason}", { reason: state.reason }) : t("closed");
    default:
      return t("not started");
  }
}

// Not a panel kind (the console puts it above the grid, not in it), but built like one.
export class ConnectionStatus extends PanelElement {
  #lines = new Map();
  #states = new Map();
  #sessionAlert;
  #loginLink;
  #tickTimer = 0;
  #robotName = t("the robot");

  disconnectedCallback() {
    super.disconnectedCallback();
    clearInterval(this.#tickTimer);
    this.#tickTimer = 0;
  }

  set loginUrl(url) {
    this.ensureBuilt();
    this.#loginLink.href = url;
  }

  set robotName(name) {
    this.#robotName = String(name);
  }

  /** Whether the robot answers the lab server (the sockets' "connected" says nothing about it). */
  set robotOnline(online) {
    this.ensureBuilt();
    const { line, text } = this.#lines.get("robot");
    line.dataset.phase = online ? "open" : "closed";
    text.textContent = online ? t("answering") : t("not answering: commands wait until it is back");
  }

  /** Show the latest state of the socket called `name`. */
  update(name, state) {
    this.ensureBuilt();
    this.#states.set(name, state);
    this.#render(name);
    if (state.phase === "closed" && state.code === CLOSE_CODES.NOT_LOGGED_IN) this.#sessionAlert.hidden = false;
    this.#syncTicker();
  }

  build() {
    this.classList.add("panel", "connection-status");
    const list = h("ul", { class: "connections", role: "list", "aria-label": t("Connections") });
    const lines = [...Object.entries(LABELS), ["robot", t("Robot")]];
    for (const [name, label] of lines) {
      const text = h("span", { class: "connection__text", "data-field": `${name}-connection`,
        text: name === "robot" ? t("checking…") : t("not started") });
      const line = h("li", { class: "connection", "data-connection": name, "data-phase": "idle" },
        h("span", { class: "connection__dot", "aria-hidden": "true" }),
        h("span", { class: "connection__name", text: `${label}:` }), " ", text);
      this.#lines.set(name, { line, text });
      list.append(line);
    }
    this.#loginLink = h("a", { href: "/login", text: t("log in again") });
    this.#sessionAlert = h("p", { class: "connection__session", id: "session-ended", role: "alert", hidden: true },
      t("Your session has ended — "), this.#loginLink, ".");
    this.append(h("h2", { class: "visually-hidden", text: t("Connection status") }), list, this.#sessionAlert);
  }

  #render(name) {
    const entry = this.#lines.get(name);
    const state = this.#states.get(name);
    if (!entry || !state) return;
    entry.line.dataset.phase = state.phase;
    if (state.code !== null && state.code !== undefined) entry.line.dataset.code = String(state.code);
    else delete entry.line.dataset.code;
    const text = describeState(state, { robotName: this.#robotName });
    if (entry.text.textContent !== text) entry.text.textContent = text;
  }

  // The "reconnecting in N s" countdown needs a clock only while some socket is waiting.
  #syncTicker() {
    const waiting = [...this.#states.values()].some((state) => state.phase === "reconnecting");
    if (waiting && !this.#tickTimer) {
      this.#tickTimer = setInterval(() => { for (const name of this.#states.keys()) this.#render(name); }, 1000);
    } else if (!waiting && this.#tickTimer) {
      clearInterval(this.#tickTimer);
      this.#tickTimer = 0;
    }
  }
}

export const register = elementRegistrar("connection-status", ConnectionStatus,
  [new URL("./connection-status.css", import.meta.url)]);
