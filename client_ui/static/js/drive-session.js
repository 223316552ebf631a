// Turns "the person wants this velocity" into the drive socket protocol: sequence numbers,
// 20 Hz repeats while a command is held (the robot's deadman expects them), and a stop on release.

import { isStill } from "./drive-math.js";
import { parseJsonMessage } from "./transport.js";

const DEFAULT_SEND_INTERVAL_MS = 50;
const STILL = Object.freeze({ linear_mps: 0, angular_radps: 0 });

/**
 * Drive protocol over one reconnecting Channel.
 *
 * Events: "ready" (detail: the server's ready message), "ack", "error" (detail: the message),
 * "sent" (detail: the message sent).
 */
export class DriveSession extends EventTarget {
  #channel;
  #sequence = 0;
  #command = STILL;
  #repeatTimer = 0;
  #sendIntervalMs = DEFAULT_SEND_INTERVAL_MS;

  constructor(channel) {
    super();
    this.#channel = channel;
    channel.addEventListener("open", () => this.#onOpen());
    channel.addEventListener("message", (event) => this.#onMessage(event.detail));
  }

  get command() {
    return this.#command;
  }

  /** Ask for a velocity; a still command sends one stop and ends the repeats. */
  setCommand(command) {
    const wasMoving = !isStill(this.#command);
    this.#command = { linear_mps: command.linear_mps, angular_radps: command.angular_radps };
    if (isStill(this.#command)) {
      this.#stopRepeating();
      if (wasMoving) this.#send({ type: "stop" });
      return;
    }
    this.#sendCurrent();
    this.#startRepeating();
  }

  /** Stop now, whatever was held; used on blur, hidden tab and page hide. */
  stop() {
    this.#command = STILL;
    this.#stopRepeating();
    this.#send({ type: "stop" });
  }

  #onOpen() {
    // Sequence numbers are per socket: the server's counter starts again with each connection.
    this.#sequence = 0;
    if (!isStill(this.#command)) this.#sendCurrent();
  }

  #onMessage(data) {
    if (typeof data !== "string") return;
    const message = parseJsonMessage(data);
    if (!message) return;
    if (message.type === "ready") {
      const interval = Number(message.send_interval_ms);
      if (Number.isFinite(interval) && interval >= 10) this.#sendIntervalMs = interval;
      if (this.#repeatTimer) this.#startRepeating();
      this.dispatchEvent(new CustomEvent("ready", { detail: message }));
    } else if (message.type === "ack") {
      this.dispatchEvent(new CustomEvent("ack", { detail: message }));
    } else if (message.type === "error") {
      this.dispatchEvent(new CustomEvent("error", { detail: message }));
    } else if (message.type === "status") {
      this.dispatchEvent(new CustomEvent("status", { detail: message }));
    }
  }

  #sendCurrent() {
    this.#send({ type: "drive", ...this.#command });
  }

  #send(body) {
    if (!this.#channel.isOpen) return;
    const message = { type: body.type, sequence: ++this.#sequence, ...body };
    this.#channel.sendJson(message);
    this.dispatchEvent(new CustomEvent("sent", { detail: message }));
  }

  #startRepeating() {
    clearInterval(this.#repeatTimer);
    this.#repeatTimer = setInterval(() => this.#sendCurrent(), this.#sendIntervalMs);
  }

  #stopRepeating() {
    clearInterval(this.#repeatTimer);
    this.#repeatTimer = 0;
  }
}
