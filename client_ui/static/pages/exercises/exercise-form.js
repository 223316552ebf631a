// The catalogue's form (templates/exercises/form.html): gathers an exercise's definition and sends it to
// POST /api/exercises (a new one) or PUT /api/exercises/<slug>. It checks nothing itself: the API checks every field,
// and its refusal is shown beside the field it names (each control's data-api-field is the API's name for it, with
// start[0] written start.0; a name that stands for a group, such as start, is its first control).
import { EditorView, basicSetup } from "codemirror";
import { EditorState } from "@codemirror/state";
import { python } from "@codemirror/lang-python";
import { fetchJson } from "../../lib/transport.js";
import { number, t } from "../../lib/i18n.js";

const form = document.getElementById("exercise-form");
const status = form.querySelector("[data-field=form-status]");
const kind = form.querySelector("#f-kind");
const random = form.querySelector("#f-random");
const region = form.querySelector("[data-slot=region]");
const slugInput = form.querySelector("#f-slug");
const titleInput = form.querySelector("#f-title");

// The template's editor: the exercise page's CodeMirror, in place of the textarea (which stays, hidden, as its
// fallback). Tab is not bound, so the keyboard leaves the editor as it leaves any field.
const textarea = form.querySelector("#f-template");
const editorHost = document.createElement("div");
editorHost.className = "exercise__editor exercise-form__editor";
editorHost.dataset.apiField = textarea.dataset.apiField;
const editor = new EditorView({
  parent: editorHost,
  state: EditorState.create({ doc: textarea.value, extensions: [basicSetup, python(), EditorView.lineWrapping,
    EditorView.cspNonce.of(form.dataset.styleNonce ?? ""),
    EditorView.contentAttributes.of({ "aria-labelledby": "f-template-label",
      "aria-describedby": "f-template-hint f-template-error" })] }),
});
textarea.after(editorHost);
textarea.hidden = true;
delete textarea.dataset.apiField;
const templateLabel = form.querySelector("#f-template-label");
templateLabel.removeAttribute("for");
templateLabel.addEventListener("click", () => editor.focus());

kind.addEventListener("change", showKind);
random.addEventListener("change", () => { region.hidden = !random.checked; });

// A new exercise's address name follows its title until the tutor writes one of their own.
let slugTyped = Boolean(slugInput?.value);
slugInput?.addEventListener("input", () => { slugTyped = slugInput.value !== ""; });
titleInput.addEventListener("input", () => {
  if (slugInput && !slugTyped && !form.dataset.slug) slugInput.value = slugOf(titleInput.value);
});

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const button = form.querySelector("button[type=submit]");
  clearErrors();
  button.disabled = true;
  say(t("Saving…"));
  const slug = form.dataset.slug;
  try {
    const answer = await fetchJson(slug ? `/api/exercises/${encodeURIComponent(slug)}` : "/api/exercises",
      { method: slug ? "PUT" : "POST", body: definition() });
    saved(answer.exercise);
  } catch (error) {
    refused(error);
  } finally {
    button.disabled = false;
  }
});

form.dataset.ready = "true";  // the editor is in place and the form sends what it holds

function showKind() {
  for (const numbers of form.querySelectorAll("fieldset[data-kind]")) numbers.hidden = numbers.dataset.kind !== kind.value;
}

/** What the form holds, as the API reads a definition: an empty number is sent as null (the API names it). */
function definition() {
  const value = (id) => form.querySelector(`#${id}`).value;
  const body = {
    title: value("f-title"),
    statement: value("f-statement"),
    template: editor.state.doc.toString(),
    scene: value("f-scene").trim(),
    start: ["f-start-x", "f-start-y", "f-start-theta"].map((id) => numberIn(form.querySelector(`#${id}`))),
    random_starts: null,
    time_limit_s: numberIn(form.querySelector("#f-time-limit")),
    rubric: { kind: kind.value },
  };
  if (!form.dataset.slug) body.slug = slugInput.value.trim();
  if (random.checked) {
    const pair = (name) => ["low", "high"].map((end) => numberIn(form.querySelector(`#f-region-${name}-${end}`)));
    body.random_starts = { x_m: pair("x"), y_m: pair("y"), theta_rad: pair("theta") };
  }
  const numbers = form.querySelector(`fieldset[data-kind="${CSS.escape(kind.value)}"]`);
  for (const input of numbers?.querySelectorAll("input") ?? []) {
    if (input.value.trim() === "" && "optional" in input.dataset) continue;  // the grader's default
    const name = input.dataset.apiField;
    body.rubric[name.slice(name.indexOf(".") + 1)] = numberIn(input);
  }
  return body;
}

function numberIn(input) {
  if (input.value.trim() === "") return null;
  return Number.isFinite(input.valueAsNumber) ? input.valueAsNumber : input.value;
}

function saved(exercise) {
  if (!form.dataset.slug) {
    // Created: from now on the form rewrites it, at its own address.
    form.dataset.slug = exercise.slug;
    slugInput.readOnly = true;
    history.replaceState(null, "", `/exercises/${encodeURIComponent(exercise.slug)}/edit`);
    const heading = t("Edit {title}", { title: exercise.title });
    document.querySelector("[data-field=heading]").textContent = heading;
    document.title = `${heading} · Telelab`;
  }
  const link = document.createElement("a");
  link.href = `/exercises/${encodeURIComponent(exercise.slug)}`;
  link.textContent = t("Open the exercise");
  link.dataset.field = "saved-link";
  const said = document.createElement("p");
  said.dataset.kind = "saved";
  said.textContent = t("Saved “{title}” ({slug}): {rubric}, time limit {seconds} s.", { title: exercise.title,
    slug: exercise.slug, rubric: kind.selectedOptions[0].textContent, seconds: number(exercise.time_limit_s) });
  said.append(" ", link);
  status.replaceChildren(said);
}

/** The API's refusal beside the field it names (the status repeats it, for whoever is at the Save button). */
function refused(error) {
  const control = error.field ? controlFor(error.field) : null;
  if (!control) {
    say(t("Not saved. {reason}", { reason: error.message }), "error");
    return;
  }
  const field = control.closest(".field");
  const slot = field.querySelector("[data-error]");
  slot.textContent = error.message;
  slot.hidden = false;
  field.classList.add("field--invalid");
  const input = control === editorHost ? editor.contentDOM : control;
  input.setAttribute("aria-invalid", "true");
  if (control !== editorHost) {
    input.setAttribute("aria-describedby", `${input.getAttribute("aria-describedby") ?? ""} ${slot.id}`.trim());
  }
  const label = field.querySelector("label")?.firstChild?.textContent.trim() || error.field;  // without its unit
  say(t("Not saved. {field}: {reason}", { field: label, reason: error.message }), "error");
  if (control === editorHost) editor.focus(); else control.focus();
}

/** The visible control the API's field name stands for: "rubric.x_m" is the chosen kind's x_m, "start[1]" the
 * start's y, and a group's name ("start", "random_starts.x_m") its first control. */
function controlFor(field) {
  const name = field.replace(/\[(\d+)\]/g, ".$1");
  const controls = [...form.querySelectorAll("[data-api-field]")].filter((control) => !control.closest("[hidden]"));
  return controls.find((control) => control.dataset.apiField === name)
    ?? controls.find((control) => control.dataset.apiField.startsWith(`${name}.`)) ?? null;
}

function clearErrors() {
  for (const slot of form.querySelectorAll("[data-error]")) {
    slot.hidden = true;
    slot.textContent = "";
    const field = slot.closest(".field");
    field.classList.remove("field--invalid");
    for (const input of field.querySelectorAll("[aria-invalid]")) {
      input.removeAttribute("aria-invalid");
      const described = (input.getAttribute("aria-describedby") ?? "").split(" ").filter((id) => id !== slot.id);
      if (input !== editor.contentDOM) input.setAttribute("aria-describedby", described.join(" "));
    }
  }
  editor.contentDOM.removeAttribute("aria-invalid");
}

function say(text, kindOfMessage = "info") {
  const line = document.createElement("p");
  line.dataset.kind = kindOfMessage;
  line.textContent = text;
  status.replaceChildren(line);
}

/** A title as an address name: lower-case letters, digits and -, as the API takes them. */
function slugOf(title) {
  return title.normalize("NFD").replace(/[\u0300-\u036f]/g, "").toLowerCase().replace(/[^a-z0-9]+/g, "-")
    .replace(/^-+|-+$/g, "").slice(0, 63).replace(/-+$/, "");
}
