// The tour editor: title, summary and the steps as JSON (validated by the server, errors name the field),
// plus a form to append a step. Tutors only; the server re-checks everything.
import { fetchJson } from "../../lib/transport.js";

const form = document.getElementById("tour-form");
const stepsField = form.querySelector("[name=steps]");
const result = form.querySelector("[data-field=result]");

form.querySelector("[data-action=add-step]").addEventListener("click", () => {
  let steps;
  try {
    steps = JSON.parse(stepsField.value || "[]");
  } catch {
    result.textContent = "The steps are not valid JSON; fix them before adding one.";
    return;
  }
  const data = new FormData(form);
  const step = { title: data.get("new_title"), text: data.get("new_text"), panel: data.get("new_panel"),
    condition: { type: data.get("new_condition") } };
  if (step.condition.type === "time") step.condition.seconds = Number(data.get("new_seconds"));
  const command = String(data.get("new_command") || "").trim();
  if (command) {
    try { step.command = JSON.parse(command); } catch { result.textContent = "The step's command is not valid JSON."; return; }
  }
  steps.push(step);
  stepsField.value = JSON.stringify(steps, null, 2);
  result.textContent = "Step added; save to check it.";
});

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const data = new FormData(form);
  let steps;
  try {
    steps = JSON.parse(data.get("steps"));
  } catch {
    result.textContent = "steps: not valid JSON.";
    return;
  }
  const id = form.dataset.tourId;
  try {
    const saved = await fetchJson(id ? `/api/tours/${id}` : "/api/tours", { method: id ? "PUT" : "POST",
      body: { title: data.get("title"), summary: data.get("summary"), topics: data.get("topics"), steps } });
    result.textContent = "Saved.";
    if (!id) window.location.assign(`/tours/${saved.id}/edit`);
  } catch (error) {
    result.textContent = error.field ? `${error.field}: ${error.message}` : error.message;
  }
});
