// Wiring of placed panels to their data, by the feeds each panel module declared when it registered
// (static/panels/registry.js): a socket's messages by type to properties, the robot's description to a
// property, or a feed service (an exchange that is more than a read: sessions, requests, polling) that its module
// registered in feed-services.js: this module registers those that share the console's state (the drive session,
// the skills, the maps), chat-session.js the chat, limits-service.js the low-level settings. Shared by every page
// that shows a robot's panels.
// Sockets are shared by path (one telemetry socket feeds odometry, sonar, laser, map and camera). An
// unreadable message or a panel that throws on one leaves a notice in that panel's frame.

import { ApiError, Channel, fetchJson, parseJsonMessage } from "../transport.js";
import { DriveSession } from "../drive-session.js";
import { TimingLog } from "../response-times.js";
import { timeActivation, timeDriveCommands } from "./timing-wiring.js";
import { reportTimings } from "./timing-report.js";
import "./chat-session.js";
import "./limits-service.js";
import { feedService, registerFeedService } from "./feed-services.js";
import { GUESS_FIELDS, goalParameterNames } from "../panel-descriptors.js";
import { bindFeedback, savePictureChoice } from "./feedback-wiring.js";
import { playTurnTone } from "./turn-tone.js";
import { showTakeoverBanner } from "./takeover-banner.js";
import { t } from "../i18n.js";

const FINAL_GOAL_STATES = new Set(["succeeded", "canceled", "aborted"]);
const MAP_POLL_MS = 2000;
const GOALS_POLL_MS = 2000; // a goal started elsewhere (another tab, a tour's step, a console opened again) shows
const ACTION_NOTE_MS = 10000; // "back at its dock" stays this long before the map's polls speak again
const SCENE_RETRY_MS = 5000;
const TIMINGS_SHOWN_EVERY_MS = 500;
const BOOKINGS_AHEAD_MS = 14 * 24 * 3600 * 1000;
const BOOKINGS_REFRESH_MS = 60 * 1000;
const DRAWN_PICTURE_STATUS = t("video off: picture drawn by this browser from where the robot stands");
const WITHHELD_CAMERA_STATUS = { phase: "off", reason: t("off during your obstacle-zone test (it would show the obstacles)") };
function isStatusOrError(message) {
  return message?.type === "status" || message?.type === "error";
}

export class ConsoleWiring {
  #root;
  #robotName;
  #robotPath;
  #status;
  #layout;
  #channels = new Map();        // path -> Channel
  #textListeners = new Map();   // path -> [{id, onMessage}]
  #infoListeners = [];
  #drive = null;                // {channel, session}
  #drivePads = [];
  #skills = [];                 // [{descriptor, panel, goalChannel, goalNames}]
  #maps = [];
  #actionNoteUntil = 0;         // Date.now() until which the map's note is an action's answer
  #goalViews = [];              // panels that show goals without picking them (the 3D lab view)
  #mapReaders = [];             // panels showing the occupancy grid: [{id, shown(), take(grid, answer, changed), fail}]
  #lastMapCells = null;
  #cameras = [];                // camera panels: the feedback layer follows the drive session
  #starters = [];
  #sceneLoaders = [];           // each scene-drawing panel's load(), to read the scene again
  #lastSeat = null;
  #timings = new TimingLog();   // this console's commands, timed for the response-times panel

  constructor({ root, robotName, robotPath, status, layout }) {
    this.#root = root;
    this.#robotName = robotName;
    this.#robotPath = robotPath;
    this.#status = status;
    this.#layout = layout;
    showTakeoverBanner(root, robotName); // a tutor's takeover of the student's class robot, shown at once
    window.addEventListener("online", () => this.#channels.forEach((channel) => channel.retryNow()));
  }

  // The feed services that share the console's state register here, as any other module registers its own.
  static {
    const services = {
      "camera-stream": (wiring, descriptor, panel) => wiring.#cameraStream(descriptor, panel),
      "map-grid": (wiring, descriptor, panel) => wiring.#mapGrid(descriptor, panel),
      "map-view": (wiring, descriptor, panel) => wiring.#readMap(descriptor, {
        take: (grid, answer, changed) => { if (changed) panel.map = grid; },
      }),
      "goal-target": (wiring, descriptor, panel) => wiring.#goalTarget(panel),
      "goal-view": (wiring, descriptor, panel) => { wiring.#goalViews.push(panel); },
      scene: (wiring, descriptor, panel) => wiring.#scene(descriptor, panel),
      drive: (wiring, descriptor, panel) => wiring.#drivePad(descriptor, panel),
      "skill-goals": (wiring, descriptor, panel) => wiring.#skill(descriptor, panel),
      queue: (wiring, descriptor, panel) => wiring.#queue(descriptor, panel),
      "response-times": (wiring, descriptor, panel) => wiring.#responseTimes(descriptor, panel),
    };
    for (const [name, connect] of Object.entries(services)) registerFeedService(name, connect);
  }

  /** The robot's name and the path of its sockets, for the feed services registered elsewhere. */
  get robotName() {
    return this.#robotName;
  }

  get robotPath() {
    return this.#robotPath;
  }

  /** Parsed text messages of the robot's socket at path for panel id (one socket per path, shared). */
  listen(path, id, onMessage) {
    return this.#listen(path, id, onMessage);
  }

  /** Whether the socket at path is open already (a service that must not open one of its own asks first). */
  hasChannel(path) {
    return this.#channels.has(path);
  }

  /** Runs start once every panel is placed (startAll). */
  onStart(start) {
    this.#starters.push(start);
  }

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

  // --- shared plumbing -------------------------------------------------------------------------------

  #guard(id, action) {
    try {
      action();
    } catch (error) {
      console.warn(`panel ${id} ignored a message:`, error);
      this.#layout.notify(id, t("Ignored a message this panel could not show ({message}).", { message: error.message }));
    }
  }

  #channel(path, { binary = false } = {}) {
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
        if (message?.type === "status" && typeof message.robot_online === "boolean") this.#showOnline(message.robot_online);
        for (const listener of this.#textListeners.get(path)) {
          if (!message) this.#layout.notify(listener.id, t("Ignored a message that could not be read."));
          else this.#guard(listener.id, () => listener.onMessage(message));
        }
      });
    }
    return channel;
  }

  /** Text messages of the socket at path, parsed, for panel id. */
  #listen(path, id, onMessage) {
    const channel = this.#channel(path);
    this.#textListeners.get(path).push({ id, onMessage });
    return channel;
  }

  #onInfo(listener) {
    this.#infoListeners.push(listener);
  }

  #showOnline(online) {
    const badge = this.#root.querySelector("#robot-online");
    badge.textContent = online ? t("Online") : t("Offline");
    badge.classList.toggle("badge--online", online);
    badge.classList.toggle("badge--offline", !online);
    this.#status.robotOnline = online;
  }

  async #loadRobot() {
    try {
      const robot = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}`);
      this.#showOnline(Boolean(robot.online));
      if (robot.info) for (const listener of this.#infoListeners) listener(robot.info);
    } catch (error) {
      const line = this.#root.querySelector("#console-error");
      line.textContent = error instanceof ApiError ? error.message : t("The robot's description could not be loaded.");
      line.hidden = false;
    }
  }

  // --- declared feeds --------------------------------------------------------------------------------

  /** {socket, messages}: the descriptor's channel if it is that socket, else the robot's socket of that name. */
  #socketFeed(descriptor, panel, { socket, messages }) {
    const path = descriptor.channel?.endsWith(`/${socket}`) ? descriptor.channel : `${this.#robotPath}/${socket}`;
    this.#listen(path, descriptor.id, (message) => {
      const property = Object.hasOwn(messages, message.type) ? messages[message.type] : null;
      if (property) panel[property] = message;
    });
  }

  /** {robotInfo, fields?}: the robot's description (or only those fields of it) once it is loaded. */
  #infoFeed(descriptor, panel, { robotInfo, fields }) {
    this.#onInfo((info) => this.#guard(descriptor.id, () => {
      panel[robotInfo] = fields ? Object.fromEntries(fields.map((field) => [field, info[field]])) : info;
    }));
  }

  // --- services --------------------------------------------------------------------------------------

  #cameraStream(descriptor, panel) {
    panel.robotName = this.#robotName;
    this.#cameras.push(panel);
    bindFeedback(panel);
    const path = descriptor.channel ?? `${this.#robotPath}/camera`;
    const name = path.split("/").pop();
    const open = () => this.#openCamera(descriptor, panel, path);
    // The picture first shown: this person's last choice for robots of this kind, else the admin's default.
    const kind = descriptor.picture?.kind ?? this.#robotName;
    const chosen = descriptor.picture?.chosen;
    const initial = chosen === "video" || chosen === "drawn" ? chosen
      : (descriptor.picture?.default === "drawn" ? "drawn" : "video");
    panel.source = initial;
    if (initial === "drawn") {
      this.#status.update(name, { phase: "off", reason: DRAWN_PICTURE_STATUS });
    } else {
      open();
    }
    // While the picture is drawn here the video socket is closed: a robot nobody watches renders nothing.
    panel.addEventListener("camera-source-change", ({ detail }) => {
      if (!detail.fallback) savePictureChoice(kind, detail.source); // not a choice: this browser cannot draw
      const channel = this.#channels.get(path);
      if (detail.source === "drawn" && channel) {
        this.#channels.delete(path);
        channel.close("the picture is drawn by this browser");
        // Closed on purpose, not a fault: the line says where the picture comes from instead, without alarm.
        this.#status.update(name, { phase: "off", reason: DRAWN_PICTURE_STATUS });
      } else if (detail.source === "video" && !channel) {
        open();
      }
    });
  }

  #openCamera(descriptor, panel, path) {
    const camera = this.#channel(path, { binary: true });
    let withheld = false; // refused during the viewer's obstacle-zone test: on purpose, not a fault
    camera.addEventListener("statechange", ({ detail }) => {
      if (this.#channels.get(path) === camera) panel.connected = detail.phase === "open";
      if (withheld && detail.phase === "closed") this.#status.update(path.split("/").pop(), WITHHELD_CAMERA_STATUS);
    });
    camera.addEventListener("message", ({ detail }) => {
      if (detail instanceof ArrayBuffer) {
        panel.frame = detail;
        return;
      }
      const message = parseJsonMessage(detail);
      if (!message) this.#layout.notify(descriptor.id, t("Ignored a message that could not be read."));
      else if (isStatusOrError(message)) this.#guard(descriptor.id, () => { panel.message = message; });
      if (message?.type === "error" && message.code === "obstacles_hidden" && !withheld) {
        withheld = true;
        this.#obstaclesWithheld();
      }
      if (message?.type === "status" && typeof message.robot_online === "boolean") this.#showOnline(message.robot_online);
    });
  }

  /** A map picks targets for the skills with goal x/y parameters and shows their goals' feedback. */
  #goalTarget(panel) {
    this.#maps.push(panel);
    panel.addEventListener("map-target", ({ detail }) => this.#routeTarget(panel, detail));
    panel.addEventListener("map-go", ({ detail }) => this.#goThere(panel, detail));
    panel.addEventListener("map-clear", () => this.#clearMap(panel));
    panel.addEventListener("map-dock", () => this.#returnToDock(panel));
    panel.supervising = this.#root.dataset.supervisor !== undefined;
    this.#starters.push(() => { panel.canGo = this.#skills.some((entry) => entry.goalNames); });
  }

  /** The robot's static world for views drawn in the browser, once (the browser keeps it by its version, the
   *  ETag, and asks again only to confirm); tried again while the robot does not answer. */
  #scene(descriptor, panel) {
    const load = async () => {
      try {
        const scene = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/scene`);
        panel.note = String(scene?.obstacles_hidden ?? ""); // the obstacles left out during an obstacle-zone test
        this.#guard(descriptor.id, () => { panel.scene = scene; });
      } catch (error) {
        panel.note = t("The lab's description could not be loaded: {message}", { message: error.message });
        if (error.status === 503 || error.status === 0) setTimeout(load, SCENE_RETRY_MS);
      }
    };
    this.#starters.push(load);
    this.#sceneLoaders.push(load);
  }

  /** The camera was refused for an obstacle-zone test begun while this page was open: the scene and the robot's
   *  description are read again, so the views drawn here drop the obstacles too. */
  #obstaclesWithheld() {
    for (const load of this.#sceneLoaders) load();
    this.#loadRobot();
  }

  /** The map panel: the occupancy grid and, when there is none, why. */
  #mapGrid(descriptor, panel) {
    this.#readMap(descriptor, {
      take: (grid, answer, changed) => {
        if (Date.now() >= this.#actionNoteUntil) panel.note = grid ? "" : String(answer?.message ?? "");
        if (changed) panel.grid = grid;
      },
      fail: (error) => {
        panel.grid = null;
        // A map withheld during an obstacle-zone test is no fault: its sentence says why and until when.
        panel.note = error.code === "obstacles_hidden" ? error.message : t("The map could not be loaded: {message}", { message: error.message });
      },
    });
  }

  /** One more panel showing the occupancy grid; the grid is polled (once for all of them) while one is shown. */
  #readMap(descriptor, { take, fail = () => {} }) {
    let visible = true;
    const frame = this.#layout.frameOf(descriptor.id);
    new IntersectionObserver((entries) => { visible = entries.some((e) => e.isIntersecting); }).observe(frame);
    const shown = () => visible && this.#layout.isShown(descriptor.id);
    if (!this.#mapReaders.length) {
      this.#starters.push(() => {
        this.#pollMap();
        setInterval(() => this.#pollMap(), MAP_POLL_MS);
      });
    }
    this.#mapReaders.push({ id: descriptor.id, shown, take, fail });
  }

  async #pollMap() {
    if (document.visibilityState !== "visible" || !this.#mapReaders.some((reader) => reader.shown())) return;
    try {
      const answer = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/map`);
      const grid = answer?.map ?? null;
      const changed = grid?.cells_b64 !== this.#lastMapCells;
      this.#lastMapCells = grid?.cells_b64;
      for (const reader of this.#mapReaders) this.#guard(reader.id, () => reader.take(grid, answer, changed));
    } catch (error) {
      this.#lastMapCells = null;
      for (const reader of this.#mapReaders) reader.fail(error);
    }
  }

  /** Forgets the robot's map (the controller's command); the next poll shows "No map yet". */
  async #clearMap(mapPanel) {
    try {
      const answer = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/map`, { method: "DELETE" });
      mapPanel.grid = null;
      mapPanel.note = String(answer?.message ?? ""); // the next poll's "No map yet" follows on from it
    } catch (error) {
      mapPanel.note = t("The map was not cleared: {message}", { message: error.message });
    }
  }

  /** Shows an action's answer on the map, kept over the polls' notes long enough to be read. */
  #actionNote(mapPanel, text) {
    this.#actionNoteUntil = Date.now() + ACTION_NOTE_MS;
    mapPanel.note = text;
  }

  async #returnToDock(mapPanel) {
    try {
      const answer = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/dock`, { method: "POST" });
      mapPanel.resetTrails();
      this.#actionNote(mapPanel, String(answer?.message ?? ""));
    } catch (error) {
      mapPanel.note = t("The robot was not moved: {message}", { message: error.message });
    }
  }

  /** A target picked on the map goes to the first skill whose schema has goal x/y parameters. */
  #routeTarget(mapPanel, { x_m, y_m }) {
    const skill = this.#skills.find((entry) => entry.goalNames);
    if (!skill) return;
    skill.panel.parameters = { [skill.goalNames.x]: x_m, [skill.goalNames.y]: y_m };
    mapPanel.target = [x_m, y_m];
    for (const view of this.#goalViews) view.target = [x_m, y_m];
  }

  /** "Go there": the map's target as a goal of the first goal skill, through the skill API like its Activate. */
  #goThere(mapPanel, { x_m, y_m }) {
    const skill = this.#skills.find((entry) => entry.goalNames);
    if (!skill) return;
    this.#routeTarget(mapPanel, { x_m, y_m });
    const parameters = { [skill.goalNames.x]: x_m, [skill.goalNames.y]: y_m };
    this.#activate(skill, { skill: skill.descriptor.skill, parameters, preempt: true });
  }

  #ensureDrive(path) {
    if (this.#drive) return this.#drive;
    const channel = this.#channel(path);
    const session = new DriveSession(channel);
    this.#drive = { channel, session };
    timeDriveCommands(session, this.#timings);
    session.addEventListener("ready", ({ detail }) => this.#cameras.forEach((camera) => { camera.driveReady = detail; }));
    session.addEventListener("sent", ({ detail }) => this.#cameras.forEach((camera) => { camera.driveSent = detail; }));
    return this.#drive;
  }

  #drivePad(descriptor, pad) {
    this.#drivePads.push(pad);
    pad.link = "connecting";
    const { channel, session } = this.#ensureDrive(descriptor.channel ?? `${this.#robotPath}/drive`);
    session.addEventListener("ready", ({ detail }) => {
      pad.limits = { max_linear_mps: detail.max_linear_mps, max_angular_radps: detail.max_angular_radps };
      pad.link = "ready";
    });
    session.addEventListener("ack", ({ detail }) => { pad.ack = detail; });
    session.addEventListener("error", ({ detail }) => { pad.error = detail; });
    session.addEventListener("status", ({ detail }) => { if (detail.message) pad.error = detail; });
    channel.addEventListener("statechange", ({ detail }) => {
      if (detail.phase !== "open") pad.link = detail.phase === "closed" ? "closed" : "connecting";
    });
    pad.addEventListener("drive-command", ({ detail }) => session.setCommand(detail));
    pad.addEventListener("drive-stop", () => session.stop());
  }

  #queue(descriptor, panel) {
    const queue = this.#listen(descriptor.channel ?? `${this.#robotPath}/queue`, descriptor.id, (message) => {
      if (message.type === "queue") {
        panel.seat = message;
        this.#noticeTurn(message);
        for (const pad of this.#drivePads) pad.observing = !message.is_controller;
        for (const { panel: skill } of this.#skills) skill.observing = !message.is_controller;
        for (const map of this.#maps) map.observing = !message.is_controller;
      } else if (isStatusOrError(message)) {
        panel.message = message;
      }
    });
    panel.addEventListener("queue-action", ({ detail }) => queue.sendJson({ type: detail.type }));
    panel.robotName = this.#robotName;
    const loadBookings = () => {
      const from = new Date();
      const to = new Date(from.getTime() + BOOKINGS_AHEAD_MS);
      const query = `from=${encodeURIComponent(from.toISOString())}&to=${encodeURIComponent(to.toISOString())}`;
      fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/bookings?${query}`)
        .then((answer) => { panel.bookings = answer.bookings; })
        .catch(() => { panel.bookings = null; }); // e.g. a practice robot, which takes no bookings
    };
    loadBookings();
    setInterval(loadBookings, BOOKINGS_REFRESH_MS);
  }

  /** The turn starting after a wait is announced above every tab, with a flash and a short tone. */
  #noticeTurn(seat) {
    const waited = this.#lastSeat?.in_queue && !this.#lastSeat.is_controller;
    this.#lastSeat = seat;
    const notice = this.#root.querySelector("#turn-notice");
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

  #responseTimes(descriptor, panel) {
    const show = (always = false) => {
      const nowMs = performance.now();
      this.#timings.expire(nowMs);
      if (always || this.#layout.isShown(descriptor.id)) panel.report = { log: this.#timings, nowMs };
    };
    this.#starters.push(() => {
      show(true);
      setInterval(show, TIMINGS_SHOWN_EVERY_MS);
      reportTimings(this.#timings, this.#robotName); // for the tutor's class view
    });
  }

  #skill(descriptor, panel) {
    panel.descriptor = descriptor;
    if (descriptor.schema?.some((parameter) => parameter.name === GUESS_FIELDS.x)) this.#followPose(descriptor, panel);
    const entry = { descriptor, panel, goalChannel: null, goalId: null, goalNames: goalParameterNames(descriptor.schema) };
    if (!this.#skills.length) {
      this.#starters.push(() => {
        this.#adoptRunningGoals();
        setInterval(() => this.#adoptRunningGoals(), GOALS_POLL_MS);
      });
    }
    this.#skills.push(entry);
    const base = `/api/robots/${encodeURIComponent(this.#robotName)}`;
    panel.addEventListener("skill-activate", ({ detail }) => this.#activate(entry, detail));
    panel.addEventListener("skill-cancel", async ({ detail }) => {
      try {
        const answer = await fetchJson(`${base}/goals/${encodeURIComponent(detail.goal_id)}`, { method: "DELETE" });
        this.#guard(descriptor.id, () => { panel.goal = answer.goal; });
      } catch (error) {
        panel.error = { code: error.code ?? "network", message: error.message, field: null };
      }
    });
  }

  /** Keeps a pose-guess skill's panel told the robot's best pose: the converged estimate, else the pose tracked
   *  against the floor plan, else odometry. */
  #followPose(descriptor, panel) {
    let estimate = null;
    this.#listen(`${this.#robotPath}/telemetry`, descriptor.id, (message) => {
      if (message.type === "localization") {
        const tracked = message.navigation?.source === "map tracking" ? message.navigation.pose : null;
        estimate = (message.active && message.converged ? message.estimate : null) ?? tracked;
        if (estimate) panel.currentPose = estimate;
      } else if (message.type === "telemetry" && !estimate && message.odometry?.pose) {
        panel.currentPose = message.odometry.pose;
      }
    });
  }

  async #activate(entry, { skill, parameters, preempt }) {
    const base = `/api/robots/${encodeURIComponent(this.#robotName)}`;
    try {
      // A plan used as a skill runs through the plans API, on this robot; any other skill is activated.
      const runUrl = entry.descriptor.run_url;
      const body = runUrl ? { target: this.#robotName } : { parameters, preempt: Boolean(preempt) };
      const answer = await timeActivation(this.#timings, body, () => (runUrl
        ? fetchJson(runUrl, { method: "POST", body })
        : fetchJson(`${base}/skills/${encodeURIComponent(skill)}/goals`, { method: "POST", body })));
      this.#followGoal(entry, answer.goal);
    } catch (error) {
      entry.panel.error = { code: error.code ?? "network", message: error.message, field: error.field ?? null };
    }
  }

  /** The robot's running goals, whoever started them: each skill panel shows and follows its skill's, so a panel
   *  never says Idle while its skill runs. */
  async #adoptRunningGoals() {
    const shown = this.#skills.filter((entry) => this.#layout.isShown(entry.descriptor.id));
    if (document.visibilityState !== "visible" || !shown.length) return;
    let answer;
    try {
      answer = await fetchJson(`/api/robots/${encodeURIComponent(this.#robotName)}/goals`);
    } catch {
      return; // the next look tries again; the robot's line already says when it does not answer
    }
    for (const goal of answer?.goals ?? []) {
      const entry = this.#skills.find((candidate) => candidate.descriptor.skill === goal.skill);
      if (entry && entry.goalId !== goal.goal_id) this.#followGoal(entry, goal);
    }
  }

  /** Show a goal and follow it on its socket until it ends. */
  #followGoal(entry, goal) {
    const { descriptor, panel } = entry;
    entry.goalId = goal?.goal_id ?? null;
    this.#guard(descriptor.id, () => { panel.goal = goal; });
    entry.goalChannel?.close("a newer goal replaced it");
    if (!goal?.goal_id || FINAL_GOAL_STATES.has(goal.status)) return;
    const channel = new Channel(`${this.#robotPath}/goals/${encodeURIComponent(goal.goal_id)}`);
    entry.goalChannel = channel;
    channel.addEventListener("message", ({ detail }) => {
      const message = parseJsonMessage(detail);
      if (!message) {
        this.#layout.notify(descriptor.id, t("Ignored a goal message that could not be read."));
        return;
      }
      this.#guard(descriptor.id, () => {
        if (message.type === "goal" && message.goal) {
          panel.goal = message.goal;
          const ended = FINAL_GOAL_STATES.has(message.goal.status);
          if (message.goal.feedback) this.#shareFeedback(entry, message.goal.feedback, ended);
          if (FINAL_GOAL_STATES.has(message.goal.status)) channel.close("the goal ended");
        } else if (message.type === "goal_event") {
          panel.goalEvent = message;
        } else if (message.type === "goal_feedback") {
          panel.feedback = message.feedback;
          this.#shareFeedback(entry, message.feedback);
        } else if (message.type === "error") {
          panel.error = { code: message.code, message: message.message, field: null };
        }
      });
    });
  }

  /** Go-to-goal style feedback also shows on the map (its goal and any obstacle values). */
  #shareFeedback(entry, feedback, ended = false) {
    if (!entry.goalNames) return;
    // An ended goal's path is followed no more: its goal stays shown, its path goes.
    const shown = ended ? { ...feedback, planned_path: [] } : feedback;
    for (const map of [...this.#maps, ...this.#goalViews]) map.goalFeedback = shown;
  }
}
