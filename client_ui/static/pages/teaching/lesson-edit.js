// The lesson editor: a preview of the chosen video, the cues listed in words with "Play from here", and "Add a
// cue here" at the video's position with a command built from the robot's skill schemas. The WebVTT track stays
// editable; the server checks it (every error by line) and saves it.
import { h } from "../../lib/dom.js";
import { CommandBuilder, authoringSkills, describeCommand } from "../../lib/command-builder.js";
import { ApiError, fetchJson } from "../../lib/transport.js";
import { fixed, t } from "../../lib/i18n.js";

const form = document.getElementById("lesson-form");
const errorList = form.querySelector("[data-slot=errors]");
const result = form.querySelector("[data-field=result]");
const cuesField = form.querySelector("[name=cues]");
const videoChoice = form.querySelector("[name=video_name]");
const preview = form.querySelector("[data-field=preview]");
const previewNote = form.querySelector("[data-field=preview-note]");
const cueList = form.querySelector("[data-slot=cue-list]");
const cueStart = form.querySelector("[data-field=cue-start]");
const skills = authoringSkills();
const trackDetails = form.querySelector("[data-field=track-details]");
const command = new CommandBuilder(form.querySelector("[data-slot=cue-command]"), skills, { legend: t("Command"), sounds: true });
let checked = { cues: [], errors: [] };

/** 75.25 -> "1:15.3", for people. */
function clock(seconds) {
  const whole = Math.max(0, Number(seconds) || 0);
  const minutes = Math.floor(whole / 60);
  return `${minutes}:${fixed(whole - minutes * 60, 1).padStart(4, "0")}`;
}

/** 75.25 -> "00:01:15.250", WebVTT's form. */
function timestamp(seconds) {
  const ms = Math.round(Math.max(0, seconds) * 1000);
  const part = (value, width = 2) => String(value).padStart(width, "0");
  return `${part(Math.floor(ms / 3_600_000))}:${part(Math.floor(ms / 60_000) % 60)}:${part(Math.floor(ms / 1000) % 60)}.${part(ms % 1000, 3)}`;
}

function trackOf(cues) {
  const blocks = [...cues].sort((a, b) => a.start_s - b.start_s)
    .map((cue) => `${timestamp(cue.start_s)} --> ${timestamp(cue.end_s)}\n${JSON.stringify(cue.command)}`);
  return `WEBVTT\n\n${blocks.join("\n\n")}\n`;
}

function showErrors(errors) {
  if (errors.some((error) => error.line)) trackDetails.open = true; // the lines named are in the track
  errorList.replaceChildren(...errors.map((error) => {
    const where = error.line ? t("Line {line}", { line: error.line }) : t("Lesson");
    return h("li", { text: `${where} (${error.field}): ${error.message}` });
  }));
}

function showCues() {
  if (!checked.cues.length) {
    cueList.replaceChildren(h("li", { class: "muted", text: t("No cues yet: play the video, pause, and add one below.") }));
    return;
  }
  cueList.replaceChildren(...checked.cues.map((cue, index) => h("li", { class: "authoring-list__item", "data-cue": String(index) },
    h("p", {}, h("strong", { text: `${clock(cue.start_s)}–${clock(cue.end_s)}` }), ` ${describeCommand(cue.command, skills)}`),
    h("div", { class: "authoring-list__actions" },
      h("button", { type: "button", class: "button teaching-quiet", text: t("Play from here"),
        "aria-label": t("Play the video from cue {value}", { value: index + 1 }), onclick: () => playFrom(cue.start_s) }),
      h("button", { type: "button", class: "button teaching-quiet", text: t("Remove"),
        "aria-label": t("Remove cue {value}", { value: index + 1 }), onclick: () => removeCue(index) })),
  )));
}

function values() {
  const data = new FormData(form);
  return { title: data.get("title"), summary: data.get("summary"), topics: data.get("topics"),
    video_name: data.get("video_name"), cues: data.get("cues"),
    before_exam_id: data.get("before_exam_id"), after_exam_id: data.get("after_exam_id") };
}

/** Asks the server what the track holds; lists its cues and every error. */
async function check() {
  result.textContent = t("Checking…");
  try {
    checked = await fetchJson("/api/lessons/check", { method: "POST", body: { cues: cuesField.value } });
    showErrors(checked.errors);
    showCues();
    result.textContent = checked.errors.length ? t("{length} problem(s).", { length: checked.errors.length }) : t("{length} cue(s), all valid.", { length: checked.cues.length });
  } catch (error) {
    result.textContent = error.message;
  }
}

function playFrom(seconds) {
  if (!preview.getAttribute("src")) return;
  preview.currentTime = seconds;
  preview.play().catch(() => {}); // a browser that refuses autoplay still shows the frame
}

async function removeCue(index) {
  if (checked.errors.length) {
    result.textContent = t("Fix the problems listed first: the track cannot be rewritten while it has errors.");
    return;
  }
  cuesField.value = trackOf(checked.cues.filter((_, i) => i !== index));
  await check();
}

form.querySelector("[data-action=add-cue]").addEventListener("click", async () => {
  const duration = form.querySelector("[name=cue_duration]");
  if (!duration.checkValidity() || duration.value === "") {
    result.textContent = t("Lasts: enter between 0.5 and 600 seconds.");
    duration.focus();
    return;
  }
  let built;
  try {
    built = command.value();
  } catch (error) {
    result.textContent = error.message;
    return;
  }
  const start = Math.round((preview.currentTime || 0) * 10) / 10;
  const cue = { start_s: start, end_s: start + Number(duration.value), command: built };
  await check();
  if (checked.errors.length) {
    cuesField.value = `${cuesField.value.trimEnd()}\n\n${timestamp(cue.start_s)} --> ${timestamp(cue.end_s)}\n${JSON.stringify(built)}\n`;
  } else {
    cuesField.value = trackOf([...checked.cues, cue]);
  }
  await check();
});

function followVideoChoice() {
  const name = videoChoice.value;
  if (!name) {
    preview.removeAttribute("src");
    previewNote.textContent = t("Upload or choose a video to preview it here.");
    return;
  }
  preview.src = `/lessons/videos/${encodeURIComponent(name)}`;
  previewNote.textContent = t("Previewing {name}.", { name });
}

videoChoice.addEventListener("change", followVideoChoice);
preview.addEventListener("timeupdate", () => { cueStart.textContent = clock(preview.currentTime); });
preview.addEventListener("seeked", () => { cueStart.textContent = clock(preview.currentTime); });
preview.addEventListener("error", () => { previewNote.textContent = t("This video cannot be played in this browser."); });
form.querySelector("[data-action=check]").addEventListener("click", check);

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const id = form.dataset.lessonId;
  result.textContent = t("Saving…");
  try {
    const payload = await fetchJson(id ? `/api/lessons/${id}` : "/api/lessons", { method: id ? "PUT" : "POST", body: values() });
    showErrors([]);
    result.textContent = t("Saved.");
    if (!id) window.location.assign(`/lessons/${payload.id}/edit`);
  } catch (error) {
    if (!(error instanceof ApiError) || error.status === 0) {
      result.textContent = error instanceof ApiError ? error.message : t("The lab server cannot be reached.");
      return;
    }
    const payload = error.payload ?? {};
    showErrors(payload.errors ?? [{ line: 0, field: payload.error?.field ?? "lesson", message: payload.error?.message }]);
    result.textContent = payload.error?.message ?? t("Not saved.");
  }
});

followVideoChoice();
check();
