// The tour editor: title, summary and the steps, listed as the learner meets them and added with a form whose
// command is built from the robot's skill schemas (the JSON stays available for copying between tours).
// Tutors only; the server re-checks everything and names the field of any error.
import { h } from "../../lib/dom.js";
import { CommandBuilder, authoringSkills, describeCommand } from "../../lib/command-builder.js";
import { fetchJson } from "../../lib/transport.js";
import { t } from "../../lib/i18n.js";

const form = document.getElementById("tour-form");
const stepsField = form.querySelector("[name=steps]");
const stepList = form.querySelector("[data-slot=step-list]");
const result = form.querySelector("[data-field=result]");
const skills = authoringSkills();
const command = new CommandBuilder(form.querySelector("[data-slot=step-command]"), skills,
  { optional: true, legend: t("Command (optional)") });
const panelTitles = new Map([...form.querySelectorAll("[name=new_panel] option")].map((o) => [o.value, o.textContent]));
const CONDITION_WORDS = { skill_finished: t("when the skill finishes"), manual: t("when the learner presses Next") };

function readSteps() {
  const steps = JSON.parse(stepsField.value || "[]");
  if (!Array.isArray(steps)) throw new Error("not a list");
  return steps;
}

function writeSteps(steps) {
  stepsField.value = JSON.stringify(steps, null, 2);
  showSteps();
}

function conditionWords(condition) {
  if (condition?.type === "time") return t("after {seconds} s", { seconds: Number(condition.seconds) });
  return CONDITION_WORDS[condition?.type] ?? t("when the learner presses Next");
}

function showSteps() {
  let steps;
  try {
    steps = readSteps();
  } catch {
    stepList.replaceChildren(h("li", { class: "muted", text: t("The steps' JSON below cannot be read; fix it to see the list.") }));
    return;
  }
  if (!steps.length) {
    stepList.replaceChildren(h("li", { class: "muted", text: t("No steps yet: add the first with the form below.") }));
    return;
  }
  stepList.replaceChildren(...steps.map((step, index) => h("li", { class: "authoring-list__item", "data-step": String(index) },
    h("p", {}, h("strong", { text: step.title || t("Step {value}", { value: index + 1 }) }), t(" — look at {value}", { value: panelTitles.get(step.panel) ?? step.panel })),
    step.text ? h("p", { class: "muted", text: step.text }) : null,
    h("p", { class: "small", text: t("{command}; goes on {condition}.", { command: describeCommand(step.command, skills), condition: conditionWords(step.condition) }) }),
    h("div", { class: "authoring-list__actions" },
      h("button", { type: "button", class: "button teaching-quiet", text: t("Move up"), disabled: index === 0,
        "aria-label": t("Move step {value} up", { value: index + 1 }), onclick: () => move(index, -1) }),
      h("button", { type: "button", class: "button teaching-quiet", text: t("Remove"),
        "aria-label": t("Remove step {value}", { value: index + 1 }), onclick: () => remove(index) })),
  )));
}

function move(index, by) {
  const steps = readSteps();
  const [step] = steps.splice(index, 1);
  steps.splice(index + by, 0, step);
  writeSteps(steps);
  result.textContent = t("Step moved; save to keep it.");
}

function remove(index) {
  const steps = readSteps();
  steps.splice(index, 1);
  writeSteps(steps);
  result.textContent = t("Step removed; save to keep it.");
}

form.querySelector("[data-action=add-step]").addEventListener("click", () => {
  let steps;
  try {
    steps = readSteps();
  } catch {
    result.textContent = t("The steps' JSON cannot be read; fix it before adding a step.");
    return;
  }
  const data = new FormData(form);
  const step = { title: data.get("new_title"), text: data.get("new_text"), panel: data.get("new_panel"),
    condition: { type: data.get("new_condition") } };
  if (step.condition.type === "time") step.condition.seconds = Number(data.get("new_seconds"));
  try {
    const built = command.value();
    if (built) step.command = built;
  } catch (error) {
    result.textContent = error.message;
    return;
  }
  steps.push(step);
  writeSteps(steps);
  result.textContent = t("Step {length} added; save to check and keep it.", { length: steps.length });
});

stepsField.addEventListener("input", showSteps);

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const data = new FormData(form);
  let steps;
  try {
    steps = readSteps();
  } catch {
    result.textContent = t("steps: not valid JSON.");
    return;
  }
  const id = form.dataset.tourId;
  try {
    const saved = await fetchJson(id ? `/api/tours/${id}` : "/api/tours", { method: id ? "PUT" : "POST",
      body: { title: data.get("title"), summary: data.get("summary"), topics: data.get("topics"), steps } });
    result.textContent = t("Saved.");
    if (!id) window.location.assign(`/tours/${saved.id}/edit`);
  } catch (error) {
    result.textContent = error.field ? `${error.field}: ${error.message}` : error.message;
  }
});

showSteps();
