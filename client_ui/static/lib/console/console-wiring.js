// Wiring of placed panels to their data, by the feeds each panel module declared when it registered
// (static/panels/registry.js): a socket's messages by type to properties, the robot's description to a property,
// or a feed service (an exchange that is more than a read: sessions, requests, polling) that its own module
// registered in feed-services.js. This module is the plumbing they share and the list of those modules (the
// imports below: a new service is one more line). Shared by every page that shows a robot's panels.
// Sockets are shared by path (one telemetry socket feeds odometry, sonar, laser, map and camera). An unreadable
// message or a panel that throws on one leaves a notice in that panel's frame.
//
// Services never reach into one another's state: what one must tell the others goes out as an event on the wiring:
//   "seat"                (detail: the queue's seat message)   the turn panel's; the pads, skills and maps observe
//   "drive-ready"/"drive-sent" (detail: the session's)         the drive session's; the camera's motion preview
//   "goal-feedback"       (detail: a goal skill's feedback)    the skills'; the maps and the lab view draw it
//   "obstacles-withheld"                                       the camera's; the scene and the description reload

import { ApiError, Channel, fetchJson, parseJsonMessage } from "../transport.js";
import { TimingLog } from "../response-times.js";
import { feedService } from "./feed-services.js";
import "./camera-service.js";
import "./chat-session.js";
import "./drive-service.js";
import "./limits-service.js";
import "./map-services.js";
import "./queue-service.js";
import "./response-times-service.js";
import "./scene-service.js";
import "./skill-goals.js";
import { showTakeoverBanner } from "./takeover-banner.js";
import { t } from "../i18n.js";

export class ConsoleWiring extends EventTarget {
  #root;
  #robotName;
  #robotPath;
  #status;
  #layout;
  #channels = new Map();        // path -> Channel
  #textListeners = new Map();   // path -> [{id, onMessage}]
  #infoListeners = [];
  #starters = [];
  #timings = new TimingLog();   // this console's commands, timed for the response-times panel

  constructor({ root, robotName, robotPath, status, layout }) {
    super();
    this.#root = root;
    this.#robotName = robotName;
    this.#robotPath = robotPath;
    this.#status = status;
    this.#layout = layout;
    showTakeoverBanner(root, robotName); // a tutor's takeover of the student's class robot, shown at once
    window.addEventListener("online", () => this.#channels.forEach((channel) => channel.retryNow()));
    this.addEventListener("obstacles-withheld", () => this.#loadRobot()); // its description without the obstacles
  }

  // --- the public side, for the feed services ----------------------------------------------------------

  /** The robot's name and the path of its sockets. */
  get robotName() {
    return this.#robotName;
  }

  get robotPath() {
    return this.#robotPath;
  }

  /** The page's element holding the console (its #turn-notice, its data-supervisor). */
  get root() {
    return this.#root;
  }

  /** The console's layout (frameOf, isShown, notify) and connection-status element (update). */
  get layout() {
    return this.#layout;
  }

  get status() {
    return this.#status;
  }

  /** This console's commands, timed (lib/response-times.js's TimingLog). */
  get timings() {
    return this.#timings;
  }

  /** Parsed text messages of the robot's socket at path for panel id (one socket per path, shared). */
  listen(path, id, onMessage) {
    const channel = this.channel(path);
    this.#textListeners.get(path).push({ id, onMessage });
    return channel;
  }

  /** The socket at path, opened on first use and shared after; its state shows on the connection line. */
  channel(path, { binary = false } = {}) {
    if (this.#channels.has(path)) return this.#channels.get(path);
    const channel = new Channel(path, { binary });
    const name = path.split("/").pop();
    this.#channels.set(path, channel);
    this.#status.update(name, channel.state);
    channel.addEventListener("statechange", ({ detail }) => this.#status.update(name, detail));
    if (!binary) {
      this.#textListeners.set(path, []);
      channel.addEventListener("message", ({ detail }) => {
        const message = parseJsonMessage(detail);
        if (message?.type === "status" && typeof message.robot_online === "boolean") this.showOnline(message.robot_online);
        for (const listener of this.#textListeners.get(path)) {
          if (!message) this.#layout.notify(listener.id, t("Ignored a message that could not be read."));
          else this.guard(listener.id, () => listener.onMessage(message));
        }
      });
    }
    return channel;
  }

  /** Whether the socket at path is open already (a service that must not open one of its own asks first). */
  hasChannel(path) {
    return this.#channels.has(path);
  }

  /** Closes the socket at path on purpose (for reason); the next channel(path) opens a new one. */
  closeChannel(path, reason) {
    const channel = this.#channels.get(path);
    this.#channels.delete(path);
    this.#textListeners.delete(path);
    channel?.close(reason);
  }

  /** Runs action for panel id; what it throws becomes a notice in that panel's frame. */
  guard(id, action) {
    try {
      action();
    } catch (error) {
      console.warn(`panel ${id} ignored a message:`, error);
      this.#layout.notify(id, t("Ignored a message this panel could not show ({message}).", { message: error.message }));
    }
  }

  /** Runs start once every panel is placed (startAll). */
  onStart(start) {
    this.#starters.push(start);
  }

  /** The robot's online badge. */
  showOnline(online) {
    const badge = this.#root.querySelector("#robot-online");
    badge.textContent = online ? t("Online") : t("Offline");
    badge.classList.toggle("badge--online", online);
    badge.classList.toggle("badge--offline", !online);
    this.#status.robotOnline = online;
  }

  // --- the page's side ---------------------------------------------------------------------------------

  /** Connect one placed panel to the feeds its module declared. */
  wire(descriptor, panel, feeds) {
    for (const feed of feeds) {
      const connect = feed.service ? feedService(feed.service) : null;
      if (feed.socket) this.#socketFeed(descriptor, panel, feed);
      else if (feed.robotInfo) this.#infoFeed(descriptor, panel, feed);
      else if (connect) connect(this, descriptor, panel);
      else throw new Error(`its feed ${JSON.stringify(feed)} is not one this console offers`);
    }
  }

  /** Start what needs every panel placed first: the robot's description and the clocks. */
  startAll() {
    this.#loadRobot();
    for (const start of this.#starters) start();
  }

  async #loadRobot() {
    try {
      const robot = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}`);
      this.showOnline(Boolean(robot.online));
      if (robot.info) for (const listener of this.#infoListeners) listener(robot.info);
    } catch (error) {
      const line = this.#root.querySelector("#console-error");
      line.textContent = error instanceof ApiError ? error.message : t("The robot's description could not be loaded.");
      line.hidden = false;
    }
  }

  /** {socket, messages}: the descriptor's channel if it is that socket, else the robot's socket of that name. */
  #socketFeed(descriptor, panel, { socket, messages }) {
    const path = descriptor.channel?.endsWith(`/${socket}`) ? descriptor.channel : `${this.#robotPath}/${socket}`;
    this.listen(path, descriptor.id, (message) => {
      const property = Object.hasOwn(messages, message.type) ? messages[message.type] : null;
      if (property) panel[property] = message;
    });
  }

  /** {robotInfo, fields?}: the robot's description (or only those fields of it) once it is loaded. */
  #infoFeed(descriptor, panel, { robotInfo, fields }) {
    this.#infoListeners.push((info) => this.guard(descriptor.id, () => {
      panel[robotInfo] = fields ? Object.fromEntries(fields.map((field) => [field, info[field]])) : info;
    }));
  }
}
