// The practice robot page: start or stop one's own simulated robot, and watch its camera.
import { fetchJson } from "../../lib/transport.js";
import { attachCamera } from "./tour-camera.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("practice");
const statusLine = root.querySelector("[data-field=status]");
const startButton = root.querySelector("[data-action=start]");
const stopButton = root.querySelector("[data-action=stop]");
const camera = root.querySelector("img");
const FOLLOW_EVERY_MS = 1000;
let channel = null;
let following = null;

function sentence(state, wasStarting) {
  if (state.running) {
    return t("Your practice robot {name} is running ({in_use} of {cap} in use). ", { name: state.name, in_use: state.in_use, cap: state.cap })
      + t("It stops after {value} minutes unused.", { value: Math.round(state.idle_stop_s / 60) });
  }
  if (state.starting) return t("Your practice robot is starting…");
  if (wasStarting) return t("Your practice robot did not start. Try again in a moment.");
  return t("Your practice robot is off ({in_use} of {cap} in use).", { in_use: state.in_use, cap: state.cap });
}

function render(state) {
  const wasStarting = root.dataset.starting === "true";
  root.dataset.running = String(state.running);
  root.dataset.starting = String(Boolean(state.starting));
  startButton.hidden = state.running || Boolean(state.starting);
  stopButton.hidden = !state.running;
  camera.hidden = !state.running;  // an image with no source yet draws as a broken picture
  statusLine.textContent = sentence(state, wasStarting);
  clearTimeout(following);
  if (state.starting) following = setTimeout(follow, FOLLOW_EVERY_MS);
  if (state.running && !channel) channel = attachCamera(camera, "/ws/practice/camera");
  if (!state.running && channel) { channel.close(); channel = null; camera.removeAttribute("src"); }
}

async function act(method) {
  startButton.disabled = stopButton.disabled = true;
  statusLine.textContent = method === "POST" ? t("Starting your robot…") : t("Stopping your robot…");
  try {
    render(await fetchJson("/api/practice", { method }));
  } catch (error) {
    statusLine.textContent = error.message;
    root.dataset.error = error.code;
  } finally {
    startButton.disabled = stopButton.disabled = false;
  }
}

async function follow() {
  try {
    render(await fetchJson("/api/practice"));
  } catch (error) {
    statusLine.textContent = error.message;
    following = setTimeout(follow, FOLLOW_EVERY_MS);
  }
}

startButton.addEventListener("click", () => act("POST"));
stopButton.addEventListener("click", () => act("DELETE"));
fetchJson("/api/practice").then(render, (error) => { statusLine.textContent = error.message; });
