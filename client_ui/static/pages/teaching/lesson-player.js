// The lesson page: a video, its metadata cue track, and the robot it drives. The browser's cue events
// (oncuechange) and media events decide when to send; the commands themselves stay on the server, which
// runs the stored command of a cue by its number. Latencies are measured from the event's own timestamp.
import { fetchJson } from "../../lib/transport.js";
import { playTone, showCaption } from "./lesson-sound.js";
import { CuePlayback, cueIndexOf, summarize } from "./lesson-playback.js";
import { showLessonRobot } from "./lesson-robot.js";
import { fixed, t } from "../../lib/i18n.js";

const root = document.getElementById("lesson");
const video = root.querySelector("video");
const trackElement = video.querySelector("track");
const targetSelect = root.querySelector("[data-field=target]");
const statusLine = root.querySelector("[data-field=status]");
const captionLine = root.querySelector("[data-field=sound-caption]");
const logList = root.querySelector("[data-slot=log]");
const lessonId = Number(root.dataset.lessonId);
const MAX_LOG = 60;
const MAX_HOLD_S = 10;
const START_S = 0.5; // a paused video sought back this near its start starts the lesson again

const series = { cueToAck: [], middlewareToAck: [], pauseDetect: [], pauseToAck: [] };
let cues = [];
let renewTimer = null;
let lastEventStamp = 0;

function log(text, kind = "info") {
  const item = document.createElement("li");
  item.className = `lesson-log__item lesson-log__item--${kind}`;
  item.textContent = `${fixed(video.currentTime, 2)} s · ${text}`;
  item.dataset.kind = kind;
  logList.prepend(item);
  while (logList.children.length > MAX_LOG) logList.lastElementChild.remove();
}

function showStatus(text, isError = false) {
  statusLine.textContent = text;
  statusLine.classList.toggle("lesson__status--error", isError);
}

function formatMs(value) {
  return value === null ? "–" : t("{value} ms", { value: fixed(value, 1) });
}

function renderLatency() {
  for (const [name, values] of Object.entries(series)) {
    const stats = summarize(values);
    const cell = root.querySelector(`[data-latency="${name}"]`);
    if (cell) cell.textContent = stats.count ? `${formatMs(stats.mean)} (n=${stats.count})` : "–";
  }
}

function activeIndex() {
  const active = trackElement.track.activeCues;
  return active && active.length ? cueIndexOf(active[0].id) : null;
}

function clearRenewal() {
  if (renewTimer !== null) clearTimeout(renewTimer);
  renewTimer = null;
}

async function run(index, why) {
  const eventStamp = lastEventStamp || performance.now();
  const cue = cues.find((c) => c.index === index);
  const remaining = cue ? cue.end_s - video.currentTime : MAX_HOLD_S;
  const holdS = Math.min(MAX_HOLD_S, Math.max(0.1, remaining));
  clearRenewal();
  log(t("cue {index} ({why}) → {cue}", { index, why, cue: describe(cue) }), "run");
  try {
    const answer = await fetchJson(`/api/lessons/${lessonId}/cues/${index}/run`, {
      method: "POST", body: { target: targetSelect.value, hold_s: Number(holdS.toFixed(3)) }, // data, not text: sent to the server
    });
    const total = performance.now() - eventStamp;
    series.cueToAck.push(total);
    series.middlewareToAck.push(answer.middleware_to_ack_ms);
    renderLatency();
    const goal = answer.goal ? t("goal {status}", { status: answer.goal.status }) : t("applied");
    log(t("cue {index} acknowledged: {goal} in {total} ms", { index, goal, total: fixed(total, 1) }), "ack");
    root.dataset.lastGoal = answer.goal ? answer.goal.goal_id : "";
    if (answer.sound) {
      playTone(answer.sound);
      showCaption(captionLine, answer.sound);
      log(t("cue {index}: the robot plays a sound: {caption}", { index, caption: answer.sound.caption }), "sound");
    }
    // A drive longer than direct_control's 10 s is renewed while its cue still runs.
    if (cue && "drive" in cue.command && remaining > MAX_HOLD_S && playback.running === index) {
      renewTimer = setTimeout(() => { if (playback.running === index) { playback.running = null; playback.cueChange(index); } },
        (MAX_HOLD_S - 0.5) * 1000);
    }
    showStatus(t("The robot runs cue {index}.", { index }));
  } catch (error) {
    log(t("cue {index} refused: {message}", { index, message: error.message }), "error");
    showStatus(error.message, true);
  }
}

async function stop(why) {
  const eventStamp = lastEventStamp || performance.now();
  series.pauseDetect.push(performance.now() - eventStamp);
  clearRenewal();
  log(t("stop ({why})", { why }), "stop");
  try {
    await fetchJson("/api/lessons/stop", { method: "POST", body: { target: targetSelect.value } });
    if (why !== "cue-exit") series.pauseToAck.push(performance.now() - eventStamp);
    renderLatency();
    log(t("stop ({why}) acknowledged", { why }), "ack");
    showStatus(why === "end" ? t("The lesson has ended; the robot stopped.") : t("The robot stopped."));
  } catch (error) {
    log(t("stop refused: {message}", { message: error.message }), "error");
    showStatus(error.message, true);
  }
}

function describe(cue) {
  if (!cue) return "?";
  const command = cue.command;
  if ("skill" in command) return command.skill.replaceAll("_", " ");
  if ("drive" in command) return t("drive {linear_mps} m/s, {angular_radps} rad/s", { linear_mps: command.drive.linear_mps, angular_radps: command.drive.angular_radps });
  if ("sound" in command) return t("sound {frequency_hz} Hz: {caption}", { frequency_hz: command.sound.frequency_hz, caption: command.sound.caption });
  return "stop";
}

const playback = new CuePlayback({ run, stop });

function on(target, type, handler) {
  target.addEventListener(type, (event) => {
    lastEventStamp = event.timeStamp;  // same clock as performance.now()
    handler(event);
  });
}

/** Tells the server the video was seen to its end (the tutors' analytics); a failure only misses that record. */
async function noteWatched() {
  try { await fetchJson(`/api/lessons/${lessonId}/watched`, { method: "POST" }); } catch { /* not recorded */ }
}

async function start() {
  try {
    const lesson = await fetchJson(`/api/lessons/${lessonId}`);
    cues = lesson.cues;
  } catch (error) {
    showStatus(error.message, true);
    return;
  }
  const track = trackElement.track;
  track.mode = "hidden";  // cue events fire, nothing is drawn over the video
  on(track, "cuechange", () => playback.cueChange(activeIndex()));
  on(video, "play", () => playback.play());
  on(video, "playing", () => playback.play());
  on(video, "pause", () => { if (!video.ended) playback.pause(); });
  on(video, "seeking", () => playback.seekStart());
  on(video, "seeked", () => playback.seekEnd(video.paused, activeIndex()));
  on(video, "waiting", () => playback.buffering());
  on(video, "ended", () => { playback.ended(); noteWatched(); });
  on(video, "seeked", () => { if (video.paused && video.currentTime < START_S) placeAtStart(); });
  root.dataset.ready = "true";
  await placeAtStart();
}

/** The robot goes where the video starts (a practice robot: its dock) before the first cue, so its picture and
 *  the video's begin alike; the server says where it stands. */
async function placeAtStart() {
  try {
    const answer = await fetchJson(`/api/lessons/${lessonId}/start`, { method: "POST",
      body: { target: targetSelect.value } });
    root.dataset.startedAt = answer.at;
    log(answer.message, "start");
    showStatus(t("{message} Press play: the robot follows the video.", { message: answer.message }));
  } catch {
    showStatus(t("Press play: the robot follows the video.")); // e.g. the practice robot is off: the page offers it
  }
}

showLessonRobot(root.querySelector("[data-slot=robot-panels]"), targetSelect, video,
  root.querySelector("[data-field=readings]"));
start();
