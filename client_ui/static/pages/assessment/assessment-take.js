// Taking an attempt: answers saved as you go; the countdown follows the server's clock and the page reloads
// (showing the attempt submitted as it stood) when the server says the time is up. Submitting with questions left
// unanswered asks once more, naming them. Decides nothing itself.
import { ApiError, fetchJson } from "../../lib/transport.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("attempt");
const form = document.getElementById("answers-form");
const timeLeft = document.getElementById("time-left");
const status = document.getElementById("save-status");
const attemptId = root.dataset.attemptId;
let remainingS = timeLeft ? Number(timeLeft.dataset.remainingS) : null;
let syncedAt = performance.now();

function answerOf(fieldset) {
  const item = fieldset.dataset.item;
  if (item === "task") {
    const x = fieldset.querySelector('[name="report-x_m"]');
    return x ? ["report", { x_m: x.value, y_m: fieldset.querySelector('[name="report-y_m"]').value }] : null;
  }
  const many = [...fieldset.querySelectorAll('input[type="checkbox"]:checked')].map((box) => Number(box.value));
  if (fieldset.querySelector('input[type="checkbox"]')) return [item, many];
  const radio = fieldset.querySelector('input[type="radio"]:checked');
  if (fieldset.querySelector('input[type="radio"]')) return [item, radio ? Number(radio.value) : null];
  const value = fieldset.querySelector(`[name="q-${item}-value"]`);
  if (value) {
    const unit = fieldset.querySelector(`[name="q-${item}-unit"]`);
    return [item, { value: value.value, unit: unit ? unit.value : "" }];
  }
  return [item, fieldset.querySelector(`[name="q-${item}"]`).value];
}

/** [status, body] of a JSON request; status 0 when the server could not be reached. */
async function send(method, path, body) {
  try {
    return [200, await fetchJson(path, { method, body })];
  } catch (error) {
    if (error instanceof ApiError) return [error.status, error.payload ?? {}];
    throw error;
  }
}

async function save(fieldset) {
  const pair = answerOf(fieldset);
  if (!pair) return;
  const [code, body] = await send("PATCH", `/api/attempts/${attemptId}/answers`, { answers: { [pair[0]]: pair[1] } });
  if (code === 200) status.textContent = t("Answer saved.");
  else if (code === 409) window.location.reload();  // time up or submitted elsewhere: show what the server has
  else status.textContent = (body.error && body.error.message) || t("The answer was not saved; try again.");
}

function isAnswered(fieldset) {
  const pair = answerOf(fieldset);
  if (!pair) return true;
  const answer = pair[1];
  if (Array.isArray(answer)) return answer.length > 0;
  if (answer === null) return false;
  // A numeric answer is its value (a bare number is read in the question's unit); a report needs every coordinate.
  if (typeof answer === "object" && "value" in answer) return String(answer.value).trim() !== "";
  if (typeof answer === "object") return Object.values(answer).every((part) => String(part).trim() !== "");
  return String(answer).trim() !== "";
}

const warning = document.getElementById("unanswered");
let warnedAbout = "";
form.addEventListener("submit", (event) => {
  const missing = [...form.querySelectorAll("fieldset[data-item]")].filter((fieldset) => !isAnswered(fieldset))
    .map((fieldset) => fieldset.querySelector("legend").firstChild.textContent.trim());
  const names = missing.join(", ");
  if (!missing.length || names === warnedAbout) return;
  event.preventDefault();
  warnedAbout = names;
  const count = missing.length === 1 ? t("1 question is") : t("{length} questions are", { length: missing.length });
  warning.textContent = t("{count} not answered: {names}. Answer them, or press Submit again to hand in as it is.", { count, names });
  warning.hidden = false;
  warning.scrollIntoView({ block: "center" });
});

form.addEventListener("change", (event) => {
  const fieldset = event.target.closest("fieldset[data-item]");
  if (fieldset) save(fieldset);
});

function edited(field) {
  if (field.type === "checkbox" || field.type === "radio") return field.checked !== field.defaultChecked;
  if (field.tagName === "SELECT") return [...field.options].some((option) => option.selected !== option.defaultSelected);
  return field.value !== field.defaultValue;
}

// An answer typed while this module was still loading changed the form before anyone listened: save it now.
for (const fieldset of form.querySelectorAll("fieldset[data-item]")) {
  if ([...fieldset.querySelectorAll("input, select, textarea")].some(edited)) save(fieldset);
}

function show() {
  if (remainingS === null) return;
  const left = Math.max(0, remainingS - (performance.now() - syncedAt) / 1000);
  const minutes = Math.floor(left / 60);
  timeLeft.textContent = `${minutes}:${String(Math.floor(left % 60)).padStart(2, "0")}`;
  if (left <= 60) timeLeft.classList.add("countdown--urgent");
}

async function sync() {
  const [code, body] = await send("GET", `/api/attempts/${attemptId}`);
  if (code !== 200) return;
  if (body.attempt.status !== "in_progress") { window.location.reload(); return; }
  remainingS = body.attempt.remaining_s;
  syncedAt = performance.now();
}

if (timeLeft) {
  setInterval(show, 250);
  // Ask the server often near the end: it alone decides when the time is up.
  const poll = () => sync().finally(() => setTimeout(poll, remainingS !== null && remainingS < 15 ? 1000 : 5000));
  setTimeout(poll, 1000);
}
