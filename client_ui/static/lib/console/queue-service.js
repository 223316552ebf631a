// The turn panel's feed service ("queue"): the robot's queue socket (opening it joins the queue), the panel's
// actions sent on it, and the robot's bookings of the next two weeks. Each seat message goes out on the wiring as
// "seat" (the drive pads, skills and maps observe while someone else controls the robot); a turn that starts after
// a wait is announced above every tab (#turn-notice), with a flash and a short tone.

import { fetchJson } from "../transport.js";
import { perConsole, registerFeedService } from "./feed-services.js";
import { playTurnTone } from "./turn-tone.js";

const BOOKINGS_AHEAD_MS = 14 * 24 * 3600 * 1000;
const BOOKINGS_REFRESH_MS = 60 * 1000;

const lastSeatOf = perConsole(() => ({ seat: null }));

/** The turn starting after a wait is announced above every tab, with a flash and a short tone. */
function noticeTurn(wiring, seat) {
  const last = lastSeatOf(wiring);
  const waited = last.seat?.in_queue && !last.seat.is_controller;
  last.seat = seat;
  const notice = wiring.root.querySelector("#turn-notice");
  if (!notice) return;
  if (!seat.is_controller) {
    notice.hidden = true;
    return;
  }
  if (!waited) return;
  notice.hidden = false;
  notice.classList.remove("turn-notice--flash");
  void notice.offsetWidth; // restarts the flash animation
  notice.classList.add("turn-notice--flash");
  playTurnTone();
}

/** Connects a turn panel to the queue socket and the robot's bookings. */
export function connectQueue(wiring, descriptor, panel) {
  const queue = wiring.listen(descriptor.channel ?? `${wiring.robotPath}/queue`, descriptor.id, (message) => {
    if (message.type === "queue") {
      panel.seat = message;
      noticeTurn(wiring, message);
      wiring.dispatchEvent(new CustomEvent("seat", { detail: message }));
    } else if (message.type === "status" || message.type === "error") {
      panel.message = message;
    }
  });
  panel.addEventListener("queue-action", ({ detail }) => queue.sendJson({ type: detail.type }));
  panel.robotName = wiring.robotName;
  const loadBookings = () => {
    const from = new Date();
    const to = new Date(from.getTime() + BOOKINGS_AHEAD_MS);
    const query = `from=${encodeURIComponent(from.toISOString())}&to=${encodeURIComponent(to.toISOString())}`;
    fetchJson(`/api/robots/${encodeURIComponent(wiring.robotName)}/bookings?${query}`)
      .then((answer) => { panel.bookings = answer.bookings; })
      .catch(() => { panel.bookings = null; }); // e.g. a practice robot, which takes no bookings
  };
  loadBookings();
  setInterval(loadBookings, BOOKINGS_REFRESH_MS);
}

registerFeedService("queue", connectQueue);
