// Taking an attempt: answers saved as you go; the countdown follows the server's clock and the page reloads
// (showing the attempt submitted as it stood) when the server says the time is up. Decides nothing itself.
const root = document.getElementById("attempt");
const form = document.getElementById("answers-form");
const timeLeft = document.getElementById("time-left");
const status = document.getElementById("save-status");
const attemptId = root.dataset.attemptId;
const csrf = document.querySelector('meta[name="csrf-token"]').content;
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

async function send(method, path, body) {
  const response = await fetch(path, {
    method, headers: { "Content-Type": "application/json", "X-CSRFToken": csrf, Accept: "application/json" },
    body: body === undefined ? undefined : JSON.stringify(body), credentials: "same-origin",
  });
  return [response.status, await response.json().catch(() => ({}))];
}

async function save(fieldset) {
  const pair = answerOf(fieldset);
  if (!pair) return;
  const [code, body] = await send("PATCH", `/api/attempts/${attemptId}/answers`, { answers: { [pair[0]]: pair[1] } });
  if (code === 200) status.textContent = "Answer saved.";
  else if (code === 409) window.location.reload();  // time up or submitted elsewhere: show what the server has
  else status.textContent = (body.error && body.error.message) || "The answer was not saved; try again.";
}

form.addEventListener("change", (event) => {
  const fieldset = event.target.closest("fieldset[data-item]");
  if (fieldset) save(fieldset);
});

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
