// The lab console page: fetches the robot's description, places the panels, and wires each panel
// to its socket. It knows which panels exist, not how they draw; rules stay on the server.

import { ApiError, Channel, fetchJson, parseJsonMessage } from "./transport.js";
import { DriveSession } from "./drive-session.js";
import { h } from "./dom.js";
import * as cameraPanel from "../panels/camera-panel/camera-panel.js";
import * as drivePad from "../panels/drive-pad/drive-pad.js";
import * as odometryPanel from "../panels/odometry-panel/odometry-panel.js";
import * as connectionStatus from "../panels/connection-status/connection-status.js";
import * as chatPanel from "../panels/chat-panel/chat-panel.js";
import * as queuePanel from "../panels/queue-panel/queue-panel.js";
import { connectChat } from "./chat-session.js";

// Where each panel goes. Later the middleware will send these descriptors (see ARCHITECTURE §5).
const LAYOUT = [
  { module: connectionStatus, tag: "connection-status", slot: "status" },
  { module: cameraPanel, tag: "camera-panel", slot: "main" },
  { module: queuePanel, tag: "queue-panel", slot: "side" },
  { module: drivePad, tag: "drive-pad", slot: "side" },
  { module: odometryPanel, tag: "odometry-panel", slot: "side" },
  { module: chatPanel, tag: "chat-panel", slot: "side" },
];

function placePanels(root) {
  const panels = {};
  for (const { module, tag, slot } of LAYOUT) {
    module.register();
    const panel = h(tag);
    root.querySelector(`[data-slot="${slot}"]`).append(panel);
    panels[tag] = panel;
  }
  return panels;
}

function showPageError(root, text) {
  const line = root.querySelector("#console-error");
  line.textContent = text;
  line.hidden = !text;
}

function showOnline(root, online) {
  const badge = root.querySelector("#robot-online");
  badge.textContent = online ? "Online" : "Offline";
  badge.classList.toggle("badge--online", online);
  badge.classList.toggle("badge--offline", !online);
}

/** Route a text message that is a status or an error to a panel's `message` property. */
function isStatusOrError(message) {
  return message?.type === "status" || message?.type === "error";
}

async function loadRobot(root, robotName, pad) {
  try {
    const robot = await fetchJson(`/api/robots/${encodeURIComponent(robotName)}`);
    showOnline(root, Boolean(robot.online));
    if (robot.info) pad.limits = { max_linear_mps: robot.info.max_linear_mps, max_angular_radps: robot.info.max_angular_radps };
  } catch (error) {
    showPageError(root, error instanceof ApiError ? error.message : "The robot's description could not be loaded.");
  }
}

function connectCamera(robotPath, panels, onStatus) {
  const camera = new Channel(`${robotPath}/camera`, { binary: true });
  camera.addEventListener("statechange", ({ detail }) => { panels["camera-panel"].connected = detail.phase === "open"; });
  camera.addEventListener("message", ({ detail }) => {
    if (detail instanceof ArrayBuffer) {
      panels["camera-panel"].frame = detail;
      return;
    }
    const message = parseJsonMessage(detail);
    if (isStatusOrError(message)) panels["camera-panel"].message = message;
    if (message?.type === "status") onStatus(message);
  });
  return camera;
}

function connectTelemetry(robotPath, panels, onStatus) {
  const telemetry = new Channel(`${robotPath}/telemetry`);
  telemetry.addEventListener("message", ({ detail }) => {
    const message = parseJsonMessage(detail);
    if (message?.type === "telemetry") panels["odometry-panel"].telemetry = message;
    else if (isStatusOrError(message)) panels["odometry-panel"].message = message;
    if (message?.type === "status") onStatus(message);
  });
  return telemetry;
}

function connectDrive(robotPath, panels) {
  const pad = panels["drive-pad"];
  const drive = new Channel(`${robotPath}/drive`);
  const session = new DriveSession(drive);
  session.addEventListener("ready", ({ detail }) => {
    pad.limits = { max_linear_mps: detail.max_linear_mps, max_angular_radps: detail.max_angular_radps };
    pad.link = "ready";
  });
  session.addEventListener("ack", ({ detail }) => { pad.ack = detail; });
  session.addEventListener("error", ({ detail }) => { pad.error = detail; });
  session.addEventListener("status", ({ detail }) => { if (detail.message) pad.error = detail; });
  drive.addEventListener("statechange", ({ detail }) => {
    if (detail.phase !== "open") pad.link = detail.phase === "closed" ? "closed" : "connecting";
  });
  pad.addEventListener("drive-command", ({ detail }) => session.setCommand(detail));
  pad.addEventListener("drive-stop", () => session.stop());
  return drive;
}

function connectQueue(robotPath, panels) {
  const queue = new Channel(`${robotPath}/queue`);
  const panel = panels["queue-panel"];
  queue.addEventListener("message", ({ detail }) => {
    const message = parseJsonMessage(detail);
    if (message?.type === "queue") {
      panel.seat = message;
      panels["drive-pad"].observing = !message.is_controller;
    } else if (isStatusOrError(message)) {
      panel.message = message;
    }
  });
  panel.addEventListener("queue-action", ({ detail }) => queue.sendJson({ type: detail.type }));
  return queue;
}

function start() {
  const root = document.querySelector("#console[data-robot]");
  if (!root) return;
  const robotName = root.dataset.robot;
  const robotPath = `/ws/robots/${encodeURIComponent(robotName)}`;
  const panels = placePanels(root);

  const status = panels["connection-status"];
  status.robotName = robotName;
  status.loginUrl = root.dataset.loginUrl || "/login";
  panels["camera-panel"].robotName = robotName;
  panels["drive-pad"].link = "connecting";

  loadRobot(root, robotName, panels["drive-pad"]);

  const onStatus = (message) => {
    if (typeof message.robot_online === "boolean") showOnline(root, message.robot_online);
  };
  const channels = {
    camera: connectCamera(robotPath, panels, onStatus),
    telemetry: connectTelemetry(robotPath, panels, onStatus),
    drive: connectDrive(robotPath, panels),
    queue: connectQueue(robotPath, panels),
  };
  for (const [name, channel] of Object.entries(channels)) {
    status.update(name, channel.state);
    channel.addEventListener("statechange", ({ detail }) => status.update(name, detail));
  }
  window.addEventListener("online", () => Object.values(channels).forEach((channel) => channel.retryNow()));
  connectChat(robotPath, panels["chat-panel"]);
}

start();
