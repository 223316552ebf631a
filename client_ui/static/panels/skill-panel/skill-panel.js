// <skill-panel>: the visual proxy of one skill controller, generated from the skill's parameter schema.
// In: `descriptor` ({skill, title, motor, schema: [param]}), `goal` (goal object), `goalEvent`
//     ({kind, message, sim_time_s}), `feedback` (feedback object), `error` ({code, message, field} or null),
//     `parameters` ({name: value}: fill fields, e.g. from a click on the map), `observing` (true while
//     someone else has the turn: the panel is read-only, so nobody presses Activate only to be refused),
//     `currentPose` ({x_m, y_m, theta_rad}: keeps a pose guess, initial_*, filled until the person types one).
// Out: "skill-activate" (detail {skill, parameters, preempt}), "skill-cancel" (detail {skill, goal_id}).
// The browser's constraint validation gives early hints; the server's verdict is shown next to the field.
// Compact, so the Navigate tab's seven skills do not fill five screens: the fields a person sets each time (a goal's
// x/y, a pose guess, else the first parameter) are shown, the others fold under "Settings" (opened by itself when one of them is refused),
// and the progress and figures appear once a goal runs.

import { h } from "../../lib/dom.js";
import { GUESS_FIELDS, goalParameterNames } from "../../lib/panel-descriptors.js";
import { parameterLabel, readValue, shortNumber } from "../../lib/parameters.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed as localFixed, t } from "../../lib/i18n.js";

const ACTIVE = new Set(["accepted", "executing", "canceling"]);
const MAX_EVENTS = 30;
const DEG_PER_RAD = 180 / Math.PI;
const STATUS_WORDS = {
  accepted: t("Accepted"), executing: t("Running"), canceling: t("Canceling…"), succeeded: t("Succeeded"),
  canceled: t("Canceled"), aborted: t("Aborted"),
};

/** A skill's state word for people: "goal_blocked" -> "goal blocked". */
export function stateWords(state) {
  // A complex skill's state is "step:its state" ("back to the start:driving"): read as "back to the start: driving".
  return String(state).replaceAll("_", " ").replace(/:(?=\S)/g, ": ");
}

function fixed(value, decimals) {
  const number = Number(value);
  return Number.isFinite(number) ? localFixed(number, decimals) : "—";
}

const PARAMETER_TYPES = new Set(["double", "int", "bool", "enum", "string"]);

function checkParameter(parameter, index) {
  if (parameter === null || typeof parameter !== "object" || Array.isArray(parameter)) return t("parameter {value} is not an object", { value: index + 1 });
  if (typeof parameter.name !== "string" || !parameter.name) return t("parameter {value} has no name", { value: index + 1 });
  if (!PARAMETER_TYPES.has(parameter.type)) return t("parameter {name} has an unknown type", { name: parameter.name });
  if (parameter.type === "enum" && !Array.isArray(parameter.choices)) return t("parameter {name} has no choices", { name: parameter.name });
  return "";
}

/** What is wrong with a skill descriptor for this panel (in words), or "" when the panel can be generated. */
export function checkSkillDescriptor(descriptor) {
  if (typeof descriptor.skill !== "string" || !descriptor.skill) return t("the skill panel names no skill");
  if (!Array.isArray(descriptor.schema)) return t("the skill panel has no parameter schema");
  for (const [index, parameter] of descriptor.schema.entries()) {
    const problem = checkParameter(parameter, index);
    if (problem) return problem;
  }
  return "";
}

let panelCount = 0;

export class SkillPanel extends PanelElement {
  #descriptor = null;
  #uid = `skill-${(panelCount += 1)}`;
  #form;
  #inputs = new Map();   // name -> {parameter, input, errorLine}
  #activate;
  #cancel;
  #preempt;
  #formError;
  #status;
  #progress;
  #fields = {};
  #events;
  #result;
  #latest;
  #observingNote;
  #more;
  #figures;
  #goal = null;
  #currentPose = null;
  #guessEdited = false;

  set descriptor(descriptor) {
    this.#descriptor = descriptor;
    this.rebuild();
  }

  get descriptor() {
    return this.#descriptor;
  }

  /** Fill some fields (for instance a goal picked on the map) without activating. */
  set parameters(values) {
    this.ensureBuilt();
    for (const [name, value] of Object.entries(values ?? {})) {
      const entry = this.#inputs.get(name);
      if (!entry) continue;
      if (entry.parameter.type === "bool") entry.input.checked = Boolean(value);
      else entry.input.value = typeof value === "number" ? String(Math.round(value * 100) / 100) : String(value);
      this.#clearFieldError(entry);
    }
  }

  /** The robot's best pose now ({x_m, y_m, theta_rad}: the localized estimate, else odometry). A skill that takes
   * a pose guess (initial_x_m, initial_y_m, initial_theta_rad) keeps its guess filled from it until the person
   * types their own; "Use the current pose" fills it again. */
  set currentPose(pose) {
    this.#currentPose = pose;
    if (!this.#guessEdited) this.#fillGuess();
  }

  #fillGuess() {
    const pose = this.#currentPose;
    if (!pose || !this.#inputs.has(GUESS_FIELDS.x)) return;
    this.parameters = { [GUESS_FIELDS.x]: pose.x_m, [GUESS_FIELDS.y]: pose.y_m, [GUESS_FIELDS.theta]: pose.theta_rad };
  }

  /** Read-only while someone else has the turn (the server refuses an observer's goals anyway). */
  set observing(observing) {
    this.ensureBuilt();
    if (!this.#form) return;
    this.toggleAttribute("data-observing", Boolean(observing));
    this.#observingNote.hidden = !observing;
    for (const control of this.#form.querySelectorAll("input, select, button")) {
      control.disabled = Boolean(observing) || (control === this.#cancel && !ACTIVE.has(this.#goal?.status));
    }
  }

  /** The goal as the server reports it; drives the buttons and the result line. */
  set goal(goal) {
    this.ensureBuilt();
    if (!goal || typeof goal !== "object" || typeof goal.status !== "string") return;
    const isNewGoal = goal.goal_id !== this.#goal?.goal_id;
    this.#goal = goal;
    if (isNewGoal) {
      this.#events.replaceChildren();
      this.#latest.hidden = true;
    }
    this.dataset.status = goal.status;
    this.dataset.goalId = String(goal.goal_id ?? "");
    this.#figures.hidden = false;
    this.#status.textContent = STATUS_WORDS[goal.status] ?? goal.status;
    const active = ACTIVE.has(goal.status);
    this.#cancel.disabled = !active || goal.status === "canceling";
    if (goal.feedback) this.feedback = goal.feedback;
    if (!active) {
      const reached = goal.goal_reached ? t(" The goal was reached.") : "";
      const code = goal.error_code ? ` (${stateWords(goal.error_code).toLowerCase()})` : "";
      this.#result.textContent = `${STATUS_WORDS[goal.status] ?? goal.status}${code}: ${goal.message || t("no details.")}${reached}`;
      this.#result.dataset.outcome = goal.status;
      this.#result.hidden = false;
      if (goal.status === "succeeded") this.#progress.value = 1;
    } else {
      this.#result.hidden = true;
    }
  }

  set goalEvent(event) {
    this.ensureBuilt();
    if (!event || typeof event.kind !== "string") return;
    const time = Number.isFinite(Number(event.sim_time_s)) ? `${localFixed(event.sim_time_s, 1)} s · ` : "";
    this.#events.prepend(h("li", { "data-event": event.kind }, `${time}${stateWords(event.kind)}`,
      event.message ? `: ${event.message}` : ""));
    if (event.message && event.kind !== "started") { // the newest news stays in sight (the status says it started)
      this.#latest.textContent = t("Latest: {message}", { message: event.message });
      this.#latest.hidden = false;
    }
    while (this.#events.children.length > MAX_EVENTS) this.#events.lastElementChild.remove();
  }

  set feedback(feedback) {
    this.ensureBuilt();
    if (!feedback || typeof feedback !== "object") return;
    const progress = Number(feedback.progress);
    if (Number.isFinite(progress)) this.#progress.value = Math.min(1, Math.max(0, progress));
    this.#fields.state.textContent = typeof feedback.state === "string" ? stateWords(feedback.state) : "—";
    this.#fields.distance.textContent = fixed(feedback.distance_error_m, 3);
    this.#fields.heading.textContent = fixed(Number(feedback.heading_error_rad) * DEG_PER_RAD, 1);
    const pose = feedback.pose ?? {};
    this.#fields.pose.textContent = `${t("({x_m}, {y_m}) m", { x_m: fixed(pose.x_m, 2), y_m: fixed(pose.y_m, 2) })}, ${fixed(Number(pose.theta_rad) * DEG_PER_RAD, 0)}°`
      + (feedback.pose_source ? t(" by {pose_source}", { pose_source: feedback.pose_source }) : "");
  }

  /** A refusal of the last activation or cancel: shown next to its field, or above the buttons. */
  set error(error) {
    this.ensureBuilt();
    for (const entry of this.#inputs.values()) this.#clearFieldError(entry);
    this.#preempt.hidden = true;
    if (!error) {
      this.#formError.hidden = true;
      return;
    }
    const entry = error.field ? this.#inputs.get(error.field) : null;
    if (entry) {
      entry.input.closest("details")?.setAttribute("open", "");
      entry.errorLine.textContent = error.message || t("This value was refused.");
      entry.errorLine.hidden = false;
      entry.input.setAttribute("aria-invalid", "true");
      entry.input.focus();
      this.#formError.hidden = true;
      return;
    }
    this.#formError.textContent = error.message || t("The skill could not be started.");
    this.#formError.hidden = false;
    this.#preempt.hidden = error.code !== "busy";
  }

  #clearFieldError(entry) {
    entry.errorLine.hidden = true;
    entry.errorLine.textContent = "";
    entry.input.removeAttribute("aria-invalid");
  }

  build() {
    if (!this.#descriptor) return false; // the panel is generated from its descriptor
    const descriptor = this.#descriptor;
    this.classList.add("panel", "skill");
    this.dataset.skill = descriptor.skill;
    this.#form = h("form", { class: "skill__form", onsubmit: (event) => this.#submit(event, false) });
    const goal = goalParameterNames(descriptor.schema);
    const guess = descriptor.schema.some((parameter) => parameter.name === GUESS_FIELDS.x);
    const everyTime = new Set(guess ? Object.values(GUESS_FIELDS) : goal ? [goal.x, goal.y]
      : descriptor.schema.slice(0, 1).map((parameter) => parameter.name));
    const settings = h("div", { class: "skill__settings" });
    for (const parameter of descriptor.schema) {
      const shown = everyTime.has(parameter.name);
      (shown ? this.#form : settings).append(this.#field(parameter, shown));
    }
    const folded = descriptor.schema.length - [...everyTime].filter((name) => this.#inputs.has(name)).length;
    this.#more = folded ? h("details", { class: "skill__more", "data-field": "skill-settings" },
      h("summary", { text: t("Settings ({folded})", { folded }) }), settings) : null;
    this.#activate = h("button", { type: "submit", class: "button button--primary", "data-action": "activate",
      text: t("Activate") });
    this.#cancel = h("button", { type: "button", class: "button button--secondary", "data-action": "cancel",
      text: t("Deactivate"), disabled: true, onclick: () => this.#emitCancel() });
    this.#preempt = h("button", { type: "button", class: "button button--warn", "data-action": "preempt", hidden: true,
      text: t("Preempt it"), title: t("Stop the skill that is driving and start this one"),
      onclick: (event) => this.#submit(event, true) });
    this.#formError = h("p", { class: "skill__error", role: "alert", "data-field": "skill-error", hidden: true });
    this.#observingNote = h("p", { class: "skill__observing", "data-field": "skill-observing", hidden: true,
      text: t("You are watching: skills start during your turn.") });
    if (this.#inputs.has(GUESS_FIELDS.x)) {
      for (const name of Object.values(GUESS_FIELDS)) {
        this.#inputs.get(name)?.input.addEventListener("input", () => { this.#guessEdited = true; });
      }
      this.#form.append(h("button", { type: "button", class: "button button--secondary button--small",
        "data-action": "use-current-pose", text: t("Use the current pose"),
        title: t("Fill the guess with where the robot believes it is now"),
        onclick: () => { this.#guessEdited = false; this.#fillGuess(); } }));
    }
    this.#form.append(...(this.#more ? [this.#more] : []), this.#formError, this.#observingNote,
      h("div", { class: "skill__actions" }, this.#activate, this.#cancel, this.#preempt));

    const field = (name) => (this.#fields[name] = h("span", { "data-field": `skill-${name}`, text: "—" }));
    this.#status = h("span", { class: "skill__status", "data-field": "skill-status", text: t("Idle") });
    this.#progress = h("progress", { max: "1", value: "0", "aria-label": t("{title} progress", { title: descriptor.title }) });
    this.#events = h("ol", { class: "skill__events", "aria-label": t("{title} events", { title: descriptor.title }), "data-field": "skill-events" });
    this.#result = h("p", { class: "skill__result", role: "status", "data-field": "skill-result", hidden: true });
    this.#latest = h("p", { class: "skill__latest", "data-field": "skill-latest", hidden: true });
    this.append(
      h("h2", { class: "panel__title", text: descriptor.title }),
      h("p", { class: "skill__kind muted",
        text: descriptor.motor ? t("Motor skill: drives the wheels; only one runs at a time.")
          : t("Perceptive skill: runs beside the motor skills.") }),
      this.#form,
      h("div", { class: "skill__live", "aria-live": "polite" },
        h("p", { class: "skill__line" }, t("Status: "), this.#status, t(" · state "), field("state")),
        this.#figures = h("div", { hidden: true }, this.#progress,
          h("dl", { class: "skill__figures" },
            h("div", {}, h("dt", { text: t("Distance error") }), h("dd", {}, field("distance"), " m")),
            h("div", {}, h("dt", { text: t("Heading error") }), h("dd", {}, field("heading"), "°")),
            h("div", {}, h("dt", { text: t("Pose") }), h("dd", {}, field("pose"))))),
        this.#latest, this.#result),
      h("details", { class: "skill__log" }, h("summary", { text: t("Events") }), this.#events),
    );
  }

  /** A parameter's field; a field shown unfolded keeps its help for screen readers and as its tooltip (its label
   *  and unit say what it is), so the panel stays short. */
  #field(parameter, shown = false) {
    const id = `${this.#uid}-${parameter.name}`;
    const helpId = `${id}-help`;
    const errorId = `${id}-error`;
    const attrs = { id, name: parameter.name, "aria-describedby": `${helpId} ${errorId}`, "data-parameter": parameter.name };
    let input;
    if (parameter.type === "bool") {
      input = h("input", { ...attrs, type: "checkbox", checked: Boolean(parameter.default) });
    } else if (parameter.type === "enum") {
      input = h("select", attrs, (parameter.choices ?? []).map((choice) =>
        h("option", { value: String(choice), selected: choice === parameter.default, text: String(choice) })));
    } else if (parameter.type === "string") {
      input = h("input", { ...attrs, type: "text", value: parameter.default ?? "" });
    } else {
      input = h("input", {
        ...attrs, type: "number", inputmode: parameter.type === "int" ? "numeric" : "decimal", required: true,
        step: parameter.type === "int" ? "1" : "any",
        min: Number.isFinite(parameter.minimum) ? String(parameter.minimum) : null,
        max: Number.isFinite(parameter.maximum) ? String(parameter.maximum) : null,
        value: parameter.default === undefined || parameter.default === null ? "" : String(parameter.default),
      });
    }
    const entry = { parameter, input, errorLine: h("p", { class: "skill__field-error", id: errorId,
      "data-field-error": parameter.name, hidden: true }) };
    this.#inputs.set(parameter.name, entry);
    input.addEventListener("input", () => this.#clearFieldError(entry));
    const numeric = parameter.type === "double" || parameter.type === "int";
    const range = numeric && Number.isFinite(parameter.minimum) && Number.isFinite(parameter.maximum)
      ? t(" ({minimum} to {maximum})", { minimum: shortNumber(parameter.minimum), maximum: shortNumber(parameter.maximum) }) : "";
    if (shown) input.title = `${parameter.help ?? ""}${range}`;
    const label = h("label", { for: id }, parameterLabel(parameter.name),
      parameter.unit ? h("span", { class: "skill__unit", text: ` [${parameter.unit}]` }) : null);
    return h("div", { class: `skill__field skill__field--${parameter.type}` },
      label, input,
      h("p", { class: shown ? "skill__help visually-hidden" : "skill__help", id: helpId,
        text: `${parameter.help ?? ""}${range}` }),
      entry.errorLine);
  }

  #submit(event, preempt) {
    event.preventDefault();
    if (this.#more?.querySelector(":invalid")) this.#more.open = true; // a folded field's hint must be seen
    if (!this.#form.reportValidity()) return; // the browser's hint points at the field
    const parameters = {};
    for (const [name, { parameter, input }] of this.#inputs) {
      const value = readValue(parameter, input);
      if (value !== undefined) parameters[name] = value;
    }
    this.error = null;
    this.#result.hidden = true;
    this.emit("skill-activate", { skill: this.#descriptor.skill, parameters, preempt });
  }

  #emitCancel() {
    if (!this.#goal) return;
    this.emit("skill-cancel", { skill: this.#descriptor.skill, goal_id: this.#goal.goal_id });
  }
}

export const register = registerPanel({
  kind: "skill", tag: "skill-panel", element: SkillPanel, stylesheets: [new URL("./skill-panel.css", import.meta.url)],
  feeds: [{ service: "skill-goals" }], check: checkSkillDescriptor,
});
