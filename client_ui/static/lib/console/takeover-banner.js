// The takeover banner of a student's console: while a tutor of their class holds the robot this console drives (the
// class wall's "Take over", middleware/teaching/class_wall.py), a banner over the panels says who holds it, that the
// robot is the tutor's for now, and that control comes back; it goes the moment the tutor gives the robot back or
// leaves the wall. The news comes on the student's own class channel (/ws/class-session/wall), woken by the event
// bus in whichever worker serves it, so it shows at once; the server decides who holds the robot, this only shows
// it. A console of a robot that is not the student's class robot (a lab robot, a tutor watching) shows nothing and
// opens no channel.
import { Channel, fetchJson, parseJsonMessage } from "../transport.js";
import { adoptStylesheet, h } from "../dom.js";
import { t } from "../i18n.js";

// A console opened before its class session began looks again this often; only a practice robot's console does
// (a class seat's robot is its student's practice robot), so a lab robot's console asks once.
const CLASS_CHECK_MS = 60000;
const BACK_SHOWN_MS = 6000; // "you have your robot back" stays this long

/** Shows the takeover banner in the console at root while a tutor holds robotName; returns a stop function. */
export function showTakeoverBanner(root, robotName) {
  adoptStylesheet(new URL("./takeover-banner.css", import.meta.url));
  const banner = h("div", { class: "takeover-banner", role: "alert", "data-field": "takeover", hidden: true });
  const back = h("p", { class: "takeover-banner takeover-banner--back", role: "status", "data-field": "takeover-back",
    hidden: true });
  const panels = root.querySelector('[data-slot="panels"]');
  if (panels) panels.before(banner, back);
  else root.prepend(banner, back);
  let channel = null;
  let timer = 0;
  let backTimer = 0;
  let heldBy = null;
  let stopped = false;

  function show(tutor) {
    if (tutor === heldBy) return;
    const wasHeld = heldBy !== null;
    heldBy = tutor;
    root.dataset.takenOver = String(tutor !== null);
    if (tutor !== null) {
      clearTimeout(backTimer);
      back.hidden = true;
      banner.replaceChildren(
        h("strong", { text: t("Your tutor {tutor} has taken over this robot.", { tutor }) }), " ",
        t("It is theirs for now: your commands wait, and the robot moves as they drive it."), " ",
        t("Control comes back to you when they give it back or leave the class wall."));
      banner.hidden = false;
      return;
    }
    banner.hidden = true;
    banner.replaceChildren();
    if (wasHeld) {
      back.textContent = t("You have your robot back: your commands drive it again.");
      back.hidden = false;
      clearTimeout(backTimer);
      backTimer = setTimeout(() => { back.hidden = true; }, BACK_SHOWN_MS);
    }
  }

  function later() {
    if (!stopped && robotName.startsWith("practice-")) timer = setTimeout(check, CLASS_CHECK_MS);
  }

  function follow() {
    channel = new Channel("/ws/class-session/wall");
    channel.addEventListener("message", ({ detail }) => {
      const seat = parseJsonMessage(detail);
      if (seat?.type !== "seat") return;
      if (seat.open && seat.robot === robotName) {
        show(typeof seat.held_by === "string" && seat.held_by ? seat.held_by : null);
        return;
      }
      show(null); // the class ended, or this is not the class's robot any more
      channel.close();
      channel = null;
      later();
    });
  }

  async function check() {
    let seat;
    try {
      seat = await fetchJson("/api/class-session/wall");
    } catch {
      later();
      return;
    }
    if (stopped) return;
    if (seat?.open && seat.robot === robotName) follow();
    else later();
  }

  check();
  return () => {
    stopped = true;
    clearTimeout(timer);
    clearTimeout(backTimer);
    channel?.close();
  };
}
