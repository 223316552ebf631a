// The lesson editor: checks the cue track on the server and lists every error by line; saves.
import { ApiError, fetchJson } from "../../lib/transport.js";

const form = document.getElementById("lesson-form");
const errorList = form.querySelector("[data-slot=errors]");
const result = form.querySelector("[data-field=result]");

function showErrors(errors) {
  errorList.replaceChildren(...errors.map((error) => {
    const item = document.createElement("li");
    const where = error.line ? `Line ${error.line}` : "Lesson";
    item.textContent = `${where} (${error.field}): ${error.message}`;
    return item;
  }));
}

function values() {
  const data = new FormData(form);
  return { title: data.get("title"), summary: data.get("summary"), topics: data.get("topics"),
    video_name: data.get("video_name"), cues: data.get("cues") };
}

form.querySelector("[data-action=check]").addEventListener("click", async () => {
  result.textContent = "Checking…";
  try {
    const answer = await fetchJson("/api/lessons/check", { method: "POST", body: { cues: values().cues } });
    showErrors(answer.errors);
    result.textContent = answer.errors.length ? `${answer.errors.length} problem(s).` : `${answer.cues.length} cue(s), all valid.`;
  } catch (error) {
    result.textContent = error.message;
  }
});

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const id = form.dataset.lessonId;
  result.textContent = "Saving…";
  try {
    const payload = await fetchJson(id ? `/api/lessons/${id}` : "/api/lessons", { method: id ? "PUT" : "POST", body: values() });
    showErrors([]);
    result.textContent = "Saved.";
    if (!id) window.location.assign(`/lessons/${payload.id}/edit`);
  } catch (error) {
    if (!(error instanceof ApiError) || error.status === 0) {
      result.textContent = error instanceof ApiError ? error.message : "The lab server cannot be reached.";
      return;
    }
    const payload = error.payload ?? {};
    showErrors(payload.errors ?? [{ line: 0, field: payload.error?.field ?? "lesson", message: payload.error?.message }]);
    result.textContent = payload.error?.message ?? "Not saved.";
  }
});
