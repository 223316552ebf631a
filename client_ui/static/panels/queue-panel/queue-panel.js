// <queue-panel>: the user's seat in the robot's round-robin queue, as the queue socket reports it, and the
// robot's next bookings (a booked slot gives its holder control first).
// In: `seat` (a {"type": "queue", ...} message), `message` (status/error JSON), `bookings` (the robot's
// bookings from /api/robots/<name>/bookings, or null when they cannot be read), `robotName`.
// Out: "queue-action" CustomEvent with detail {type: "pass" | "leave" | "join"}.
// The server decides everything shown here; this panel only words it.

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { DATE_LOCALE, t } from "../../lib/i18n.js";

/** "1:05" from seconds; "—" when unknown. */
export function formatDuration(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(Number(seconds))) return "—";
  const total = Math.max(0, Math.ceil(Number(seconds)));
  return `${Math.floor(total / 60)}:${String(total % 60).padStart(2, "0")}`;
}

/** How many wait for a turn: this robot's queue (its size counts the driver too) and those waiting for any robot
 * of its kind, who may take its next turn. */
export function waitingCount(seat) {
  return Math.max(0, Number(seat.queue_size) - (seat.controller ? 1 : 0)) + (Number(seat.pool_waiting) || 0);
}

/** The sentence that says where the user stands, in the same terms as the "Waiting" figure beside it. */
export function describeSeat(seat) {
  if (!seat) return t("Joining the queue…");
  if (seat.faulted) return t("The robot is not answering. Your place is kept; the turn clock is stopped.");
  if (!seat.in_queue) return t("You are watching without a place in the queue.");
  if (seat.is_controller) {
    if (seat.turn_remaining_s !== null) {
      return waitingCount(seat) > 0 && Number(seat.queue_size) <= 1
        ? t("You have control. Others are waiting for a robot of this kind: your turn ends when the countdown does.")
        : t("You have control. Others are waiting: your turn ends when the countdown does.");
    }
    return waitingCount(seat) > 0 ? t("You have control, with no time limit for now: you go first at this time (a booking or a class).")
      : t("You have control. Nobody is waiting, so there is no time limit.");
  }
  const who = seat.controller ? t("{controller} is driving.", { controller: seat.controller }) : t("Nobody is driving.");
  const waiting = waitingCount(seat);
  if (seat.position === 1) return t("{who} You are next{value}.", { who, value: waiting > 1 ? t(" of the {waiting} waiting", { waiting }) : "" });
  return t("{who} You are number {position} of the {waiting} waiting.", { who, position: seat.position, waiting });
}

const SLOT_FORMAT = new Intl.DateTimeFormat(DATE_LOCALE, { weekday: "short", day: "numeric", month: "short",
  hour: "2-digit", minute: "2-digit" });
const END_FORMAT = new Intl.DateTimeFormat(DATE_LOCALE, { hour: "2-digit", minute: "2-digit" });

/** The bookings still to come or under way, soonest first, at most limit. */
export function upcomingBookings(bookings, nowMs, limit = 3) {
  return (Array.isArray(bookings) ? bookings : [])
    .filter((b) => (b.status === "booked" || b.status === "checked_in") && Date.parse(b.ends_at) > nowMs)
    .sort((a, b) => Date.parse(a.starts_at) - Date.parse(b.starts_at))
    .slice(0, limit);
}

/** "Mon 24 Nov, 09:00–09:30 · yours" in the browser's time zone. */
export function describeBooking(booking, nowMs) {
  const starts = Date.parse(booking.starts_at);
  const when = `${SLOT_FORMAT.format(starts)}–${END_FORMAT.format(Date.parse(booking.ends_at))}`;
  const whose = booking.mine ? t("yours") : booking.kind === "class" ? t("class {value}", { value: booking.course_code ?? "" }).trim()
    : booking.booked_by ? t("booked by {booked_by}", { booked_by: booking.booked_by }) : t("booked");
  return `${when} · ${whose}${starts <= nowMs ? ` · ${t("now")}` : ""}`;
}

/** The seat as it stands elapsedS after the server sent it: the countdown and the wait have run on. */
export function agedSeat(seat, elapsedS) {
  const less = (value) => (value === null || value === undefined ? value : Math.max(0, value - elapsedS));
  return { ...seat, turn_remaining_s: less(seat.turn_remaining_s), estimated_wait_s: less(seat.estimated_wait_s) };
}

export class QueuePanel extends PanelElement {
  #fields = {};
  #buttons = {};
  #bookingList;
  #bookingSection;
  #bookLink;
  #received = null; // { seat, at }: the last seat message and when it came
  #ticker = 0;

  build() {
    this.classList.add("panel");
    const field = (name, text = "—") => (this.#fields[name] = h("span", { "data-field": name, text }));
    const button = (type, label, help) => (this.#buttons[type] = h("button", {
      type: "button", class: "button", "data-queue-action": type, title: help, text: label,
      onclick: () => this.emit("queue-action", { type }),
    }));
    this.append(
      h("h2", { class: "panel__title", text: t("Turn") }),
      h("p", { class: "queue__summary", "aria-live": "polite" }, field("queue-summary", t("Joining the queue…"))),
      h("dl", { class: "queue__figures" },
        h("div", {}, h("dt", { text: t("Waiting") }), h("dd", {}, field("queue-size"))),
        h("div", { class: "queue__countdown" }, h("dt", { text: t("Turn ends in") }), h("dd", {}, field("turn-remaining"))),
        h("div", { class: "queue__wait" }, h("dt", { text: t("Your turn in about") }), h("dd", {}, field("estimated-wait")))),
      h("p", { class: "queue__warning", role: "alert", "data-field": "turn-warning", hidden: true,
        text: t("Your turn is about to end.") }),
      h("div", { class: "queue__actions" },
        button("pass", t("Pass the turn"), t("Give control to the next person now; you go to the end of the line")),
        button("leave", t("Leave the queue"), t("Stop waiting; you keep watching")),
        button("join", t("Join the queue"), t("Take a place at the end of the line"))),
      this.messageLine({ class: "queue__message", "data-field": "queue-message" }),
      this.#bookingSection = h("section", { class: "queue__bookings", "aria-label": t("Bookings of this robot"),
        hidden: true },
      h("h3", { class: "queue__bookings-title", text: t("Next bookings") }),
      this.#bookingList = h("ul", { class: "queue__booking-list", "data-field": "robot-bookings" }),
      this.#bookLink = h("a", { class: "queue__book-link", href: "/bookings", text: t("Book a time") })),
    );
    this.seat = null;
  }

  set robotName(name) {
    this.ensureBuilt();
    this.#bookLink.href = `/bookings?robot=${encodeURIComponent(String(name))}`;
  }

  /** The robot's bookings; null hides the list (they could not be read). */
  set bookings(bookings) {
    this.ensureBuilt();
    this.#bookingSection.hidden = bookings === null || bookings === undefined;
    const now = Date.now();
    const upcoming = upcomingBookings(bookings, now);
    this.#bookingList.replaceChildren(...(upcoming.length
      ? upcoming.map((b) => h("li", { class: b.mine ? "queue__booking--mine" : "", text: describeBooking(b, now) }))
      : [h("li", { class: "muted", text: t("None in the next two weeks: the queue decides.") })]));
  }

  /**
   * The seat message from the server. It comes when something changes (and every few seconds); the countdown
   * and the expected wait run on here, from the moment it came, so a thousand consoles need no message a second.
   */
  set seat(seat) {
    this.#received = seat ? { seat, at: performance.now() } : null;
    this.#show(seat);
    this.#tickLater();
  }

  disconnectedCallback() {
    clearTimeout(this.#ticker);
    super.disconnectedCallback?.();
  }

  #tickLater() {
    clearTimeout(this.#ticker);
    if (!this.#received) return;
    this.#ticker = setTimeout(() => {
      if (!this.isConnected || !this.#received) return;
      this.#show(agedSeat(this.#received.seat, (performance.now() - this.#received.at) / 1000));
      this.#tickLater();
    }, 1000);
  }

  #show(seat) {
    this.ensureBuilt();
    this.dataset.role = !seat ? "joining" : seat.is_controller ? "controller" : seat.in_queue ? "waiting" : "watching";
    this.#fields["queue-summary"].textContent = describeSeat(seat);
    this.#fields["queue-size"].textContent = seat ? String(waitingCount(seat)) : "—";
    // A robot that does not answer stops the clock, so no countdown or wait would be true.
    this.#fields["turn-remaining"].textContent = seat?.faulted ? "stopped" : seat?.turn_remaining_s == null
      ? t("no limit") : formatDuration(seat.turn_remaining_s);
    this.#fields["estimated-wait"].textContent = seat?.faulted ? "—" : formatDuration(seat?.estimated_wait_s);
    this.querySelector('[data-field="turn-warning"]').hidden = !seat?.warning;
    this.#buttons.pass.hidden = !(seat?.is_controller && waitingCount(seat) > 0);
    this.#buttons.leave.hidden = !seat?.in_queue;
    this.#buttons.join.hidden = !seat || seat.in_queue;
    this.querySelector(".queue__countdown").hidden = !seat?.is_controller;
    this.querySelector(".queue__wait").hidden = !seat?.in_queue || seat.is_controller;
  }

  /** A status or error from the queue socket. */
  set message(message) {
    // A status says something worth a line only when the robot went offline.
    this.showMessage(message?.type === "status" && message.robot_online !== false ? "" : message?.message ?? "");
  }
}

export const register = registerPanel({
  kind: "queue", tag: "queue-panel", element: QueuePanel, stylesheets: [new URL("./queue-panel.css", import.meta.url)],
  feeds: [{ service: "queue" }],
});
