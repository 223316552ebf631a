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
 * "sent" (detail: the message sent), "pong" (detail: {id, total_ms, robot_ms, client_ms}),
 * "ping-unsupported" (the server answered a ping with an error about its type).
 */
export class DriveSession extends EventTarget {
  #channel;
  #sequence = 0;
  #command = STILL;
  #repeatTimer = 0;
  #sendIntervalMs = DEFAULT_SEND_INTERVAL_MS;
  #pingId = 0;
  #pingsSent = new Map(); // id -> performance.now() at send
  #pongSeen = false;

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

  /** Send a ping for the response-time measurement; false when the socket is not open. */
  ping() {
    if (!this.#channel.isOpen) return false;
    const id = ++this.#pingId;
    this.#pingsSent.set(id, performance.now());
    for (const old of this.#pingsSent.keys()) if (old < id - 20) this.#pingsSent.delete(old);
    return this.#channel.sendJson({ type: "ping", id });
  }

  #onOpen() {
    this.#pingsSent.clear();
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
    } else if (message.type === "pong") {
      const sentAt = this.#pingsSent.get(message.id);
      if (sentAt === undefined) return;
      this.#pingsSent.delete(message.id);
      this.#pongSeen = true;
      const total = performance.now() - sentAt;
      const robot = Number(message.robot_rtt_ms);
      this.dispatchEvent(new CustomEvent("pong", { detail: { id: message.id, total_ms: total,
        robot_ms: Number.isFinite(robot) ? robot : NaN, client_ms: Number.isFinite(robot) ? Math.max(0, total - robot) : total } }));
    } else if (message.type === "error") {
      // A server without pings refuses them by their type; that is not the driver's problem to read.
      if (message.field === "type" && this.#pingsSent.size > 0 && !this.#pongSeen) {
        this.#pingsSent.clear();
        this.dispatchEvent(new CustomEvent("ping-unsupported", { detail: message }));
        return;
      }
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
