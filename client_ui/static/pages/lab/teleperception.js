// The teleperception exercise: polls the robot's evidence grid (reading it is what keeps the robot accumulating),
// draws the chosen layers with the robot at its odometry pose, resets the grid, exports the raw readings, and, in
// an obstacle-zone test (?attempt=<id>), lets the student drag rectangles on the grid and save them as the answer.
// The page never sees where the obstacles really are: the server grades the marks.
// The robot obeys whoever has the turn: the page shows the console's own Turn panel, whose socket takes a turn as the
// console's does (so the drive buttons work once the robot is free, and say why not while someone else has it).

import { canvasToWorld, fitView, worldToCanvas, worldTransform } from "../../lib/map-geometry.js";
import { ApiError, fetchJson } from "../../lib/transport.js";
import { gridImage } from "../../panels/map-panel/map-panel.js";
import { showRobotPanels } from "../../lib/console/robot-panels.js";
import { t } from "../../lib/i18n.js";

const POLL_MS = 1000;
const ROBOT_RADIUS_M = 0.2;
const MIN_MARK_M = 0.05;

const root = document.getElementById("teleperception");
const robot = root.dataset.robot;
const attemptId = /^\d{1,12}$/.test(root.dataset.attempt) ? root.dataset.attempt : null;
const canvas = root.querySelector("#evidence-canvas");
const errorLine = root.querySelector("[data-field=error]");
const countsLine = root.querySelector("[data-field=counts]");
const messageLine = root.querySelector("[data-field=message]");
const zoneCount = root.querySelector("[data-field=zone-count]");
const api = `/api/robots/${encodeURIComponent(robot)}`;

let evidence = null;
let image = null;
let view = null;
let rects = [];
let dragStart = null;
let dragNow = null;

function showError(error) {
  if (!error) {
    errorLine.hidden = true;
    return;
  }
  errorLine.textContent = error instanceof ApiError ? error.message : t("Something went wrong; reload the page.");
  errorLine.hidden = false;
}

function layerQuery() {
  const sonar = root.querySelector("[name=sonar]").checked;
  const laser = root.querySelector("[name=laser]").checked;
  const sensor = sonar && laser ? "both" : sonar ? "sonar" : laser ? "laser" : null;
  const part = root.querySelector("[name=part]").value;
  return sensor ? `sensor=${sensor}&part=${encodeURIComponent(part)}` : null;
}

async function poll() {
  const query = layerQuery();
  try {
    // With no layer chosen the grid is still read for its counts, so the robot keeps accumulating.
    const answer = await fetchJson(`${api}/evidence?${query ?? "sensor=both"}`);
    evidence = answer.evidence;
    image = query ? gridImage(evidence.grid) : null;
    showError(null);
  } catch (error) {
    showError(error);
  }
  draw();
}

function gridBounds(grid) {
  const size = Number(grid.resolution_m);
  return { minX: Number(grid.origin_x_m), minY: Number(grid.origin_y_m),
    maxX: Number(grid.origin_x_m) + size * Number(grid.width_cells),
    maxY: Number(grid.origin_y_m) + size * Number(grid.height_cells) };
}

function fitCanvas(bounds) {
  const width = Math.max(240, Math.round(canvas.clientWidth || 640));
  const height = Math.round(width * (bounds.maxY - bounds.minY) / (bounds.maxX - bounds.minX));
  if (canvas.width !== width || canvas.height !== height) {
    canvas.width = width;
    canvas.height = height;
  }
  return fitView(bounds, width, height, 0);
}

function draw() {
  if (!evidence) return;
  const grid = evidence.grid;
  const bounds = gridBounds(grid);
  view = fitCanvas(bounds);
  const ctx = canvas.getContext("2d");
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (image) {
    // Row 0 of the image is the lowest y: flip it into the world transform.
    ctx.save();
    ctx.imageSmoothingEnabled = false;
    ctx.setTransform(...worldTransform(view));
    ctx.translate(bounds.minX, bounds.minY);
    ctx.scale(Number(grid.resolution_m), Number(grid.resolution_m));
    ctx.drawImage(image, 0, 0);
    ctx.restore();
  }
  drawRobot(ctx, evidence.odometry);
  for (const rect of rects) drawRect(ctx, rect, "#c26a00");
  if (dragStart && dragNow) drawRect(ctx, [...dragStart, ...dragNow], "#b1261b");
  const c = evidence.counts;
  countsLine.textContent = t("Readings integrated: sonar {sonar}, laser {laser} (standing {static}, moving {moving}).",
    { sonar: c.sonar, laser: c.laser, static: c.static, moving: c.moving })
    + ` ${evidence.accumulating ? t("Accumulating while this page is open.") : t("Paused.")}`;
  canvas.dataset.drawn = String(evidence.version);
}

function drawRobot(ctx, pose) {
  const [x, y] = worldToCanvas(view, pose.x_m, pose.y_m);
  const radius = ROBOT_RADIUS_M * view.scale;
  ctx.strokeStyle = "#1d5fc4";
  ctx.fillStyle = "rgb(29 95 196 / 35%)";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.arc(x, y, radius, 0, 2 * Math.PI);
  ctx.fill();
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(x, y);
  ctx.lineTo(x + radius * 1.6 * Math.cos(pose.theta_rad), y - radius * 1.6 * Math.sin(pose.theta_rad));
  ctx.stroke();
}

function drawRect(ctx, [x0, y0, x1, y1], colour) {
  const [ax, ay] = worldToCanvas(view, Math.min(x0, x1), Math.max(y0, y1));
  const [bx, by] = worldToCanvas(view, Math.max(x0, x1), Math.min(y0, y1));
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2;
  ctx.setLineDash([6, 3]);
  ctx.strokeRect(ax, ay, bx - ax, by - ay);
  ctx.setLineDash([]);
}

function pointerWorld(event) {
  const box = canvas.getBoundingClientRect();
  const px = (event.clientX - box.left) * (canvas.width / box.width);
  const py = (event.clientY - box.top) * (canvas.height / box.height);
  return canvasToWorld(view, px, py).map((v) => Math.round(v * 100) / 100);
}

function showZoneCount() {
  zoneCount.textContent = rects.length ? t("{length} rectangle(s) marked.", { length: rects.length }) : t("No rectangle yet.");
}

async function drive(linear, angular, duration) {
  try {
    await fetchJson(`${api}/skills/direct_control/goals`, { method: "POST", body: {
      parameters: { linear_mps: linear, angular_radps: angular, duration_s: duration }, preempt: true } });
    messageLine.textContent = t("Moving: these readings go to part 2.");
    showError(null);
  } catch (error) {
    showError(error);
  }
}

async function resetGrid() {
  if (!window.confirm(t("Reset the evidence grid? Everyone watching this robot sees it emptied."))) return;
  try {
    const answer = await fetchJson(`${api}/evidence`, { method: "DELETE" });
    messageLine.textContent = answer.message;
    showError(null);
    await poll();
  } catch (error) {
    showError(error);
  }
}

async function saveZone() {
  try {
    await fetchJson(`/api/attempts/${attemptId}/answers`, { method: "PATCH", body: { answers: { zone: { rects } } } });
    messageLine.textContent = t("Saved {length} rectangle(s). Submit the test from its page when you are done.", { length: rects.length });
    showError(null);
  } catch (error) {
    showError(error);
  }
}

async function loadZone() {
  root.querySelector("#zone").hidden = false;
  try {
    const answer = await fetchJson(`/api/attempts/${attemptId}`);
    rects = answer.attempt.answers?.zone?.rects ?? [];
  } catch (error) {
    showError(error);
  }
  showZoneCount();
  draw();
}

function wireZone() {
  canvas.classList.add("is-marking");
  canvas.addEventListener("pointerdown", (event) => {
    if (!view) return;
    dragStart = pointerWorld(event);
    dragNow = dragStart;
    canvas.setPointerCapture(event.pointerId);
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!dragStart) return;
    dragNow = pointerWorld(event);
    draw();
  });
  canvas.addEventListener("pointerup", () => {
    if (dragStart && dragNow && Math.abs(dragNow[0] - dragStart[0]) >= MIN_MARK_M &&
        Math.abs(dragNow[1] - dragStart[1]) >= MIN_MARK_M) {
      const [x0, y0] = dragStart;
      const [x1, y1] = dragNow;
      rects.push([Math.min(x0, x1), Math.min(y0, y1), Math.max(x0, x1), Math.max(y0, y1)]);
      showZoneCount();
    }
    dragStart = dragNow = null;
    draw();
  });
  root.querySelector("[data-action=undo-mark]").addEventListener("click", () => {
    rects.pop();
    showZoneCount();
    draw();
  });
  root.querySelector("[data-action=save-zone]").addEventListener("click", saveZone);
  loadZone();
}

root.querySelector("[data-action=turn]").addEventListener("click", () => drive(0, 0.8, 4));
root.querySelector("[data-action=forward]").addEventListener("click", () => drive(0.2, 0, 2));
root.querySelector("[data-action=reset]").addEventListener("click", resetGrid);
for (const input of root.querySelectorAll("[name=sonar], [name=laser], [name=part]")) input.addEventListener("change", poll);
window.addEventListener("resize", draw);
if (attemptId) wireZone();
showRobotPanels(root.querySelector("[data-slot=turn]"), robot, ["queue"]);
poll();
setInterval(poll, POLL_MS);
