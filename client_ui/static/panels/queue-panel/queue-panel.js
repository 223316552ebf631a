// <queue-panel>: the user's seat in the robot's round-robin queue, as the queue socket reports it.
// In: `seat` (a {"type": "queue", ...} message), `message` (status/error JSON).
// Out: "queue-action" CustomEvent with detail {type: "pass" | "leave" | "join"}.
// The server decides everything shown here; this panel only words it.

import { adoptStylesheet, defineOnce, h } from "../../js/dom.js";

/** "1:05" from seconds; "—" when unknown. */
export function formatDuration(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(Number(seconds))) return "—";
  const total = Math.max(0, Math.ceil(Number(seconds)));
  return `${Math.floor(total / 60)}:${String(total % 60).padStart(2, "0")}`;
}

/** The sentence that says where the user stands. */
export function describeSeat(seat) {
  if (!seat) return "Joining the queue…";
  if (seat.faulted) return "The robot is not answering. Your place is kept; the turn clock is stopped.";
  if (!seat.in_queue) return "You are watching without a place in the queue.";
  if (seat.is_controller) {
    return seat.turn_remaining_s === null ? "You have control. Nobody is waiting, so there is no time limit."
      : "You have control. Others are waiting: your turn ends when the countdown does.";
  }
  const who = seat.controller ? `${seat.controller} is driving.` : "Nobody is driving.";
  return `${who} You are number ${seat.position} in line.`;
}

export class QueuePanel extends HTMLElement {
  #built = false;
  #fields = {};
  #buttons = {};

  connectedCallback() {
    this.#build();
  }

  #build() {
    if (this.#built) return;
    this.#built = true;
    this.classList.add("panel");
    const field = (name, text = "—") => (this.#fields[name] = h("span", { "data-field": name, text }));
    const button = (type, label, help) => (this.#buttons[type] = h("button", {
      type: "button", class: "button", "data-queue-action": type, title: help, text: label,
      onclick: () => this.dispatchEvent(new CustomEvent("queue-action", { detail: { type }, bubbles: true })),
    }));
    this.append(
      h("h2", { class: "panel__title", text: "Turn" }),
      h("p", { class: "queue__summary", "aria-live": "polite" }, field("queue-summary", "Joining the queue…")),
      h("dl", { class: "queue__figures" },
        h("div", {}, h("dt", { text: "In line" }), h("dd", {}, field("queue-size"))),
        h("div", { class: "queue__countdown" }, h("dt", { text: "Turn ends in" }), h("dd", {}, field("turn-remaining"))),
        h("div", { class: "queue__wait" }, h("dt", { text: "Your turn in about" }), h("dd", {}, field("estimated-wait")))),
      h("p", { class: "queue__warning", role: "alert", "data-field": "turn-warning", hidden: true,
        text: "Your turn is about to end." }),
      h("div", { class: "queue__actions" },
        button("pass", "Pass the turn", "Give control to the next person now; you go to the end of the line"),
        button("leave", "Leave the queue", "Stop waiting; you keep watching"),
        button("join", "Join the queue", "Take a place at the end of the line")),
      h("p", { class: "queue__message", "data-field": "queue-message", hidden: true }),
    );
    this.seat = null;
  }

  /** The seat message from the server. */
  set seat(seat) {
    this.#build();
    this.dataset.role = !seat ? "joining" : seat.is_controller ? "controller" : seat.in_queue ? "waiting" : "watching";
    this.#fields["queue-summary"].textContent = describeSeat(seat);
    this.#fields["queue-size"].textContent = seat ? String(seat.queue_size) : "—";
    this.#fields["turn-remaining"].textContent = seat?.turn_remaining_s == null ? "no limit"
      : formatDuration(seat.turn_remaining_s);
    this.#fields["estimated-wait"].textContent = formatDuration(seat?.estimated_wait_s);
    this.querySelector('[data-field="turn-warning"]').hidden = !seat?.warning;
    this.#buttons.pass.hidden = !(seat?.is_controller && seat.queue_size > 1);
    this.#buttons.leave.hidden = !seat?.in_queue;
    this.#buttons.join.hidden = !seat || seat.in_queue;
    this.querySelector(".queue__countdown").hidden = !seat?.is_controller;
    this.querySelector(".queue__wait").hidden = !seat?.in_queue || seat.is_controller;
  }

  /** A status or error from the queue socket. */
  set message(message) {
    this.#build();
    const line = this.#fields["queue-message"] ?? this.querySelector('[data-field="queue-message"]');
    line.textContent = message?.message ?? "";
    line.hidden = !message?.message || message.type === "status" && message.robot_online !== false;
  }
}

export function register() {
  adoptStylesheet(new URL("./queue-panel.css", import.meta.url));
  defineOnce("queue-panel", QueuePanel);
}
