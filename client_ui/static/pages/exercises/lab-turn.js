// The exercise page's lab robot: a student may submit on a lab robot during their turn on it instead of on a fresh
// simulated robot. The page joins the chosen robot's queue only when the student asks (opening the queue socket
// joins it, as the console does), then shows their seat as the console's Turn panel words it: in their turn it
// offers "Submit on <robot>"; otherwise it says who drives and where they stand, with the robot's console (its
// queue and turn) a link away. The server decides the turn; a run whose turn ends is ended by exercise.js.
//
// Events: "seat" (detail: {robot_name, seat}: the queue socket's message, or seat null when the page left the queue).
import { Channel, parseJsonMessage } from "../../lib/transport.js";
import { describeSeat } from "../../panels/queue-panel/queue-panel.js";
import { t } from "../../lib/i18n.js";

const REMEMBERED = "telelab-exercise-lab-robot";  // this tab's choice, so a reload keeps the seat (sessionStorage)

/** The lab's robots, [{name, title}]: the options the page was served with. */
export function labRobots(select) {
  return [...select.options].map((option) => ({ name: option.value, title: option.textContent.trim() }));
}

/** The seat in words for this page: the console's sentence, then what it means for submitting here. */
export function seatSentence(robotName, seat) {
  if (!seat) return t("Joining {robot_name}'s queue…", { robot_name: robotName });
  const where = describeSeat(seat);
  if (seat.is_controller && !seat.faulted) {
    return `${where} ${t("Submit on {robot_name} grades your program on it.", { robot_name: robotName })}`;
  }
  return `${where} ${t("You can submit on {robot_name} once your turn comes: it comes here, or in its console.", { robot_name: robotName })}`;
}

export class LabTurn extends EventTarget {
  #root; #select; #queueButton; #leaveButton; #submitButton; #line; #consoleLink;
  #channel = null;
  #robotName = null;
  #seat = null;
  #runningOn = null;

  constructor(root) {
    super();
    this.#root = root;
    this.#select = root.querySelector("[data-field=lab-robot]");
    this.#queueButton = root.querySelector("[data-action=lab-queue]");
    this.#leaveButton = root.querySelector("[data-action=lab-leave]");
    this.#submitButton = root.querySelector("[data-action=lab-submit]");
    this.#line = root.querySelector("[data-field=lab-turn]");
    this.#consoleLink = root.querySelector("[data-field=lab-console]");
    // Another robot chosen: this page stops following the first one's seat without leaving its queue (the console
    // may hold it), as a closed console does.
    this.#select.addEventListener("change", () => { this.#stopFollowing(); this.#showChoice(); });
    this.#queueButton.addEventListener("click", () => this.join(this.#select.value));
    this.#leaveButton.addEventListener("click", () => this.leave());
    addEventListener("pagehide", () => this.#channel?.close());
  }

  /** Lists the lab's robots; rejoins the queue this tab had joined (a reload). */
  async load() {
    const robots = labRobots(this.#select);
    this.#select.replaceChildren(...robots.map(({ name, title }) => {
      const option = document.createElement("option");
      option.value = name;
      option.textContent = title && title !== name ? `${title} (${name})` : name;
      return option;
    }));
    this.#root.dataset.robots = String(robots.length);
    if (!robots.length) {
      this.#select.closest("label").hidden = this.#queueButton.hidden = true;
      this.#consoleLink.hidden = true;
      this.#line.textContent = t("This lab has no robot to submit on: submit on a fresh simulated robot.");
      return;
    }
    const remembered = sessionStorage.getItem(REMEMBERED);
    if (robots.some((robot) => robot.name === remembered)) {
      this.#select.value = remembered;
      this.join(remembered);
    } else this.#showChoice();
  }

  /** The robot whose turn the student holds now, or null. */
  get controlled() {
    return this.#seat?.is_controller && !this.#seat.faulted ? this.#robotName : null;
  }

  /** Joins robotName's queue (the student asked) and follows their seat. */
  join(robotName) {
    this.#stopFollowing();
    this.#robotName = robotName;
    sessionStorage.setItem(REMEMBERED, robotName);
    this.#channel = new Channel(`/ws/robots/${encodeURIComponent(robotName)}/queue`);
    this.#channel.addEventListener("message", (event) => {
      const message = parseJsonMessage(event.detail);
      if (message?.type === "queue") this.#showSeat(message);
      else if (message?.type === "error") this.#line.textContent = message.message;
    });
    this.#channel.addEventListener("statechange", (event) => {
      if (event.detail.phase === "closed" && event.detail.reason && this.#robotName === robotName) {
        this.#line.textContent = event.detail.reason;
      }
    });
    this.#showSeat(null);
  }

  /** Leaves the robot's queue now (the seat goes at once, not after the grace), turn and all. */
  leave() {
    this.#channel?.sendJson({ type: "leave" });
    this.#stopFollowing();
    this.#showChoice();
  }

  #stopFollowing() {
    if (!this.#channel) return;
    this.#channel.close();
    this.#channel = null;
    sessionStorage.removeItem(REMEMBERED);
    const robotName = this.#robotName;
    this.#robotName = null;
    this.#seat = null;
    this.dispatchEvent(new CustomEvent("seat", { detail: { robot_name: robotName, seat: null } }));
  }

  /** What the page is doing: running (on runningOn, a lab robot's name, or null for the practice robot), and whether
   * Python is ready. Submit waits for Python and for no run; the robot and its queue stay put while a run goes. */
  setBusy({ running, runningOn = null, ready }) {
    this.#runningOn = running ? runningOn : null;
    this.#submitButton.disabled = running || !ready;
    this.#queueButton.disabled = this.#leaveButton.disabled = this.#select.disabled = running;
    if (this.#robotName && this.#seat) this.#line.textContent = this.#sentence();
  }

  #sentence() {
    if (this.#runningOn === this.#robotName && this.controlled) {
      return t("Your submission runs on {robot_name}: it keeps your turn until it ends.", { robot_name: this.#robotName });
    }
    return seatSentence(this.#robotName, this.#seat);
  }

  #showChoice() {
    const name = this.#select.value;
    this.#queueButton.textContent = t("Take a turn on {robot_name}", { robot_name: name });
    this.#queueButton.hidden = false;
    this.#leaveButton.hidden = this.#submitButton.hidden = true;
    this.#consoleLink.href = `/lab/${encodeURIComponent(name)}`;
    this.#consoleLink.textContent = t("Open {robot_name}'s console (its queue and turn)", { robot_name: name });
    this.#line.textContent = t("You may also submit on a lab robot during your turn on it. Take a turn here (you join its queue) or in its console.");
    this.#root.dataset.turn = "none";
  }

  #showSeat(seat) {
    const name = this.#robotName;
    if (seat && !seat.in_queue) {  // left the queue (in the console, say) or dropped from it: the choice again
      this.#stopFollowing();
      this.#showChoice();
      this.#line.textContent = seat.controller
        ? t("You have no place in {robot_name}'s queue now ({controller} is driving). Take a turn to submit on it.", { robot_name: name, controller: seat.controller })
        : t("You have no place in {robot_name}'s queue now. Take a turn to submit on it.", { robot_name: name });
      return;
    }
    this.#seat = seat;
    this.#queueButton.hidden = true;
    this.#leaveButton.hidden = false;
    this.#leaveButton.textContent = t("Leave {robot_name}'s queue", { robot_name: name });
    this.#submitButton.textContent = t("Submit on {robot_name}", { robot_name: name });
    this.#submitButton.hidden = this.controlled === null;
    this.#line.textContent = this.#sentence();
    this.#root.dataset.turn = seat === null ? "joining" : this.controlled ? "controller" : "waiting";
    if (seat) this.dispatchEvent(new CustomEvent("seat", { detail: { robot_name: name, seat } }));
  }
}
