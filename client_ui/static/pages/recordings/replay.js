// The replay page: one recording's channels (fetched once as JSON) drawn at the timeline's time: the map with the
// trails, the robot's-eye view redrawn from the scene (lib/robot-eye.js), the speed and sonar plots, the command
// log. Play, pause, speed, scrub and jumps only move the time; every view is a function of it.

import { RobotEyeRenderer } from "../../lib/robot-eye.js";
import { fitView, sceneBounds, worldToCanvas } from "../../lib/map-geometry.js";
import { fixed, t } from "../../lib/i18n.js";
import { register as registerLabView } from "../../panels/lab-view/lab-view.js";

registerLabView();

const root = document.getElementById("replay");
const $ = (selector) => root.querySelector(selector);
const timeInput = $('[data-field="time"]');
const playButton = $('[data-action="play"]');
const speedSelect = $('[data-field="speed"]');
const jumpSelect = $('[data-field="jump"]');
const status = $('[data-field="status"]');
let data = null;
let now = 0;
let playing = false;
let eye = null;
let lastFrame = 0;
const FIRST_WINDOW_S = 30;

/** The index of the last sample at or before time s (samples are [t, ...] or {t}), -1 before the first. */
export function sampleAt(samples, s) {
  let low = 0;
  let high = samples.length - 1;
  let found = -1;
  while (low <= high) {
    const mid = (low + high) >> 1;
    const at = Array.isArray(samples[mid]) ? samples[mid][0] : samples[mid].t;
    if (at <= s) { found = mid; low = mid + 1; } else { high = mid - 1; }
  }
  return found;
}

function pose(row) {
  return row ? { x_m: row[1], y_m: row[2], theta_rad: row[3] } : null;
}

function boxes() {
  return (data.scene?.blocks ?? []).map((b) => ({ center_x_m: b.center_x_m, center_y_m: b.center_y_m,
    half_x_m: b.half_x_m, half_y_m: b.half_y_m, yaw_rad: b.yaw_rad }));
}

function drawMap() {
  const canvas = $('[data-slot="map"]');
  const context = canvas.getContext("2d");
  const trails = [["odometry", "#1f6feb"], ["localization", "#d97706"], ["ground_truth", "#15803d"]];
  const points = trails.flatMap(([name]) => data[name].map((r) => ({ center_x_m: r[1], center_y_m: r[2], half_x_m: 0, half_y_m: 0, yaw_rad: 0 })));
  const view = fitView(sceneBounds([...boxes(), ...points]), canvas.width, canvas.height);
  context.clearRect(0, 0, canvas.width, canvas.height);
  context.fillStyle = "#9aa5b1";
  for (const b of boxes()) {
    const [cx, cy] = worldToCanvas(view, b.center_x_m, b.center_y_m);
    context.save();
    context.translate(cx, cy);
    context.rotate(-b.yaw_rad);
    context.fillRect(-b.half_x_m * view.scale, -b.half_y_m * view.scale, 2 * b.half_x_m * view.scale, 2 * b.half_y_m * view.scale);
    context.restore();
  }
  drawMeasurement(context, view);
  for (const [name, colour] of trails) {
    const rows = data[name];
    const last = sampleAt(rows, now);
    if (last < 0) continue;
    context.strokeStyle = colour;
    context.lineWidth = 2;
    context.beginPath();
    rows.slice(0, last + 1).forEach((r, i) => {
      const [x, y] = worldToCanvas(view, r[1], r[2]);
      if (i === 0) context.moveTo(x, y); else context.lineTo(x, y);
    });
    context.stroke();
    const [x, y] = worldToCanvas(view, rows[last][1], rows[last][2]);
    context.fillStyle = colour;
    context.beginPath();
    context.arc(x, y, 5, 0, 2 * Math.PI);
    context.fill();
    context.beginPath();
    context.moveTo(x, y);
    context.lineTo(x + 12 * Math.cos(rows[last][3]), y - 12 * Math.sin(rows[last][3]));
    context.stroke();
  }
}

/** The rubric's measurement of a test attempt's run: the target, the wall or the reported pose, in purple. */
function drawMeasurement(context, view) {
  const task = data.measurement?.task;
  if (!task) return;
  context.save();
  context.strokeStyle = "#7c3aed";
  context.fillStyle = "#7c3aed";
  context.lineWidth = 2;
  if (task.kind === "reach_point") {
    const [x, y] = worldToCanvas(view, task.x_m, task.y_m);
    context.beginPath();
    context.arc(x, y, 7, 0, 2 * Math.PI);
    context.stroke();
    const end = data.ground_truth.length ? data.ground_truth : data.odometry;
    const last = end[end.length - 1];
    if (last) {
      const [ex, ey] = worldToCanvas(view, last[1], last[2]);
      context.setLineDash([4, 3]);
      context.beginPath();
      context.moveTo(ex, ey);
      context.lineTo(x, y);
      context.stroke();
    }
  } else if (task.kind === "wall_following") {
    const [x1, y1] = worldToCanvas(view, task.x1_m, task.y1_m);
    const [x2, y2] = worldToCanvas(view, task.x2_m, task.y2_m);
    context.beginPath();
    context.moveTo(x1, y1);
    context.lineTo(x2, y2);
    context.stroke();
    const length = Math.hypot(x2 - x1, y2 - y1) || 1;
    const [nx, ny] = [-(y2 - y1) / length, (x2 - x1) / length];
    const offset = (task.distance_m ?? 0) * view.scale;
    context.setLineDash([4, 3]);
    for (const side of [1, -1]) {
      context.beginPath();
      context.moveTo(x1 + side * nx * offset, y1 + side * ny * offset);
      context.lineTo(x2 + side * nx * offset, y2 + side * ny * offset);
      context.stroke();
    }
  }
  const report = data.measurement.report;
  if (report && Number.isFinite(Number(report.x_m)) && Number.isFinite(Number(report.y_m))) {
    const [x, y] = worldToCanvas(view, Number(report.x_m), Number(report.y_m));
    context.fillRect(x - 4, y - 4, 8, 8);
  }
  context.restore();
}

function drawPlot(canvas, series, { min, max, label }) {
  const context = canvas.getContext("2d");
  const { width, height } = canvas;
  context.clearRect(0, 0, width, height);
  const span = Math.max(1e-6, data.duration_s);
  const y = (v) => height - 16 - ((v - min) / Math.max(1e-6, max - min)) * (height - 28);
  for (const [rows, column, colour] of series) {
    context.strokeStyle = colour;
    context.beginPath();
    rows.forEach((r, i) => {
      const x = (r[0] / span) * width;
      if (i === 0) context.moveTo(x, y(r[column])); else context.lineTo(x, y(r[column]));
    });
    context.stroke();
  }
  context.strokeStyle = "#c0392b";
  context.beginPath();
  context.moveTo((now / span) * width, 0);
  context.lineTo((now / span) * width, height);
  context.stroke();
  context.fillStyle = "#333";
  context.fillText(label, 4, 12);
}

function drawSonar() {
  const canvas = $('[data-slot="sonar"]');
  const context = canvas.getContext("2d");
  const { width, height } = canvas;
  context.clearRect(0, 0, width, height);
  const row = data.sonar[sampleAt(data.sonar, now)];
  context.fillStyle = "#333";
  context.fillText(t("Sonar ranges now [m]"), 4, 12);
  if (!row) return;
  const ranges = row.slice(1);
  const top = Math.max(...(data.info?.sonar_max_m ?? [3]), 0.1);
  const barWidth = width / Math.max(1, ranges.length);
  context.fillStyle = "#1f6feb";
  ranges.forEach((r, i) => {
    const h = (Math.min(r, top) / top) * (height - 24);
    context.fillRect(i * barWidth + 2, height - 4 - h, barWidth - 4, h);
  });
}

function drawCommands() {
  const items = root.querySelectorAll('[data-slot="commands"] li');
  const current = sampleAt(data.commands, now);
  items.forEach((item, i) => {
    item.classList.toggle("is-past", i < current);
    item.classList.toggle("is-current", i === current);
  });
}

function drawEye(p) {
  if (!eye || !p) return;
  try {
    eye.render(p);
  } catch (error) {
    eye = null;
    $('[data-field="eye-status"]').textContent = t("This browser cannot draw the robot's-eye view.");
  }
}

let cameraShown = -1;

function drawCamera() {
  const row = data.camera[sampleAt(data.camera, now)];
  const index = row ? row[1] : -1;
  if (index === cameraShown || index < 0) return;
  cameraShown = index;
  $('[data-slot="camera"]').src = `/api/recordings/${root.dataset.recordingId}/camera/${index}`;
}

/** The 3D view (the console's <lab-view>): the robot where it stood then, with its laser hits and sonar cones. */
function drawThree(p) {
  const view = $('[data-slot="three"]');
  if (!data.scene || !p) return;
  const laser = data.laser[sampleAt(data.laser, now)];
  const sonar = data.sonar[sampleAt(data.sonar, now)];
  view.telemetry = {
    type: "telemetry", odometry: { pose: p, linear_mps: 0, angular_radps: 0 },
    laser: laser ? { angle_min_rad: laser[1], angle_increment_rad: laser[2], ranges_m: laser[3] } : null,
    sonar: sonar ? { ranges_m: sonar.slice(1) } : null,
  };
}

function draw() {
  const odometry = pose(data.odometry[sampleAt(data.odometry, now)]);
  const truth = pose(data.ground_truth[sampleAt(data.ground_truth, now)]);
  timeInput.value = String(now);
  $('[data-field="now"]').textContent = `${fixed(now, 2)} s / ${fixed(data.duration_s, 1)} s`;
  const poseText = $('[data-field="pose"]');
  if (odometry) {
    poseText.textContent = t("Odometry: x {x} m, y {y} m, heading {th} rad", { x: fixed(odometry.x_m, 3), y: fixed(odometry.y_m, 3), th: fixed(odometry.theta_rad, 3) });
    poseText.dataset.x = String(odometry.x_m);
    poseText.dataset.y = String(odometry.y_m);
    poseText.dataset.t = String(data.odometry[sampleAt(data.odometry, now)][0]);
  }
  drawMap();
  drawEye(truth ?? odometry);
  drawThree(truth ?? odometry);
  drawPlot($('[data-slot="speed"]'), [[data.odometry, 4, "#1f6feb"], [data.odometry, 5, "#d97706"]],
    { min: -1.5, max: 1.5, label: t("Speed: linear [m/s] blue, angular [rad/s] orange") });
  drawSonar();
  drawCommands();
  drawCamera();
}

function seek(s) {
  now = Math.min(Math.max(0, s), data.duration_s);
  draw();
}

function tick(frameTime) {
  if (!playing) return;
  const elapsed = lastFrame ? (frameTime - lastFrame) / 1000 : 0;
  lastFrame = frameTime;
  seek(now + elapsed * Number(speedSelect.value));
  if (now >= data.duration_s) { setPlaying(false); return; }
  requestAnimationFrame(tick);
}

function setPlaying(on) {
  playing = on;
  playButton.textContent = on ? t("Pause") : t("Play");
  lastFrame = 0;
  if (on) {
    if (now >= data.duration_s) now = 0;
    requestAnimationFrame(tick);
  }
}

function fillLists() {
  const list = $('[data-slot="commands"]');
  data.commands.forEach((c) => {
    const button = document.createElement("button");
    button.type = "button";
    const what = c.action === "drive" ? t("drive {linear_mps} m/s, {angular_radps} rad/s", c)
      : c.action === "activate" ? `${c.skill}` : c.action === "run_plan" ? t("plan {name}", { name: c.plan_name }) : c.action;
    button.textContent = `${fixed(c.t, 2)} s · #${c.sequence} · ${c.source} · ${what}${c.accepted ? "" : ` (${t("refused")}: ${c.outcome})`}`;
    button.addEventListener("click", () => seek(c.t));
    const item = document.createElement("li");
    item.append(button);
    list.append(item);
  });
  const events = [
    ...data.goals.map((g) => ({ t: g.t, label: `${fixed(g.t, 2)} s · ${t("goal")} ${g.skill}: ${g.status}` })),
    ...data.commands.filter((c) => c.action !== "drive").map((c) => ({ t: c.t, label: `${fixed(c.t, 2)} s · ${c.action} ${c.skill || c.plan_name || ""}` })),
  ].sort((a, b) => a.t - b.t);
  for (const event of events) {
    const option = document.createElement("option");
    option.value = String(event.t);
    option.textContent = event.label;
    jumpSelect.append(option);
  }
}

async function fetchData(query) {
  const response = await fetch(`/api/recordings/${root.dataset.recordingId}/data${query}`, { credentials: "same-origin" });
  return response.ok ? response.json() : null;
}

function show(loaded) {
  data = loaded;
  timeInput.max = String(data.duration_s);
  if (data.scene) {
    if (!eye) {
      try {
        eye = new RobotEyeRenderer($('[data-slot="eye"]'), data.scene, { width_px: 320, height_px: 240 });
      } catch (error) {
        $('[data-field="eye-status"]').textContent = t("This browser cannot draw the robot's-eye view.");
      }
    }
    $('[data-slot="three"]').scene = data.scene;
  }
  if (data.measurement) {
    const m = data.measurement;
    $('[data-field="measurement"]').textContent = t("Graded: {points} of {max} points. {feedback}", {
      points: m.points ?? "–", max: m.max_points ?? "–", feedback: m.feedback ?? "" });
  }
  $('[data-slot="camera-card"]').hidden = !data.camera.length;
  seek(now);
}

async function start() {
  // The first seconds first (a long recording's first frame does not wait for all of it), then the whole.
  const first = await fetchData(`?to_s=${FIRST_WINDOW_S}`);
  if (!first) {
    status.textContent = t("The recording could not be read.");
    return;
  }
  show(first);
  root.dataset.firstFrame = "true";
  status.textContent = t("Loading the rest of the recording…");
  const whole = first.recording_s !== undefined && first.recording_s <= FIRST_WINDOW_S ? first : await fetchData("");
  if (!whole) {
    status.textContent = t("The recording could not be read.");
    return;
  }
  const scene = whole.scene ?? first.scene;
  show({ ...whole, scene });
  fillLists();
  status.textContent = t("{n} s recorded: play it, or drag the time.", { n: fixed(data.duration_s, 1) });
  root.dataset.ready = "true";
}

timeInput.addEventListener("input", () => { setPlaying(false); seek(Number(timeInput.value)); });
playButton.addEventListener("click", () => setPlaying(!playing));
jumpSelect.addEventListener("change", () => { if (jumpSelect.value !== "") seek(Number(jumpSelect.value)); });
start();
