// The practice robot page: start or stop one's own simulated robot, and watch its camera.
import { fetchJson } from "../../lib/transport.js";
import { attachCamera } from "./tour-camera.js";

const root = document.getElementById("practice");
const statusLine = root.querySelector("[data-field=status]");
const startButton = root.querySelector("[data-action=start]");
const stopButton = root.querySelector("[data-action=stop]");
const camera = root.querySelector("img");
let channel = null;

function render(state) {
  root.dataset.running = String(state.running);
  startButton.hidden = state.running;
  stopButton.hidden = !state.running;
  statusLine.textContent = state.running
    ? `Your practice robot ${state.name} is running (${state.in_use} of ${state.cap} in use). `
      + `It stops after ${Math.round(state.idle_stop_s / 60)} minutes unused.`
    : `Your practice robot is off (${state.in_use} of ${state.cap} in use).`;
  if (state.running && !channel) channel = attachCamera(camera, "/ws/practice/camera");
  if (!state.running && channel) { channel.close(); channel = null; camera.removeAttribute("src"); }
}

async function act(method) {
  startButton.disabled = stopButton.disabled = true;
  statusLine.textContent = method === "POST" ? "Starting your robot…" : "Stopping your robot…";
  try {
    render(await fetchJson("/api/practice", { method }));
  } catch (error) {
    statusLine.textContent = error.message;
    root.dataset.error = error.code;
  } finally {
    startButton.disabled = stopButton.disabled = false;
  }
}

startButton.addEventListener("click", () => act("POST"));
stopButton.addEventListener("click", () => act("DELETE"));
fetchJson("/api/practice").then(render, (error) => { statusLine.textContent = error.message; });
