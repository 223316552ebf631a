// A robot command built from fields instead of typed JSON, for the lesson and tour editors: run a skill (its
// parameters generated from the skill's schema, with units, ranges and help), drive, stop, or (where a command
// is optional) none. The server checks the command again when the lesson or tour is saved.

import { h } from "./dom.js";
import { parameterLabel, readValue, shortNumber } from "./parameters.js";
import { t } from "./i18n.js";

const MAX_LINEAR_MPS = 0.5;
const MAX_ANGULAR_RADPS = 1.5;
let nextId = 0;

/** The skills an authoring page was given (`<script type="application/json" id="authoring-skills">`), or []. */
export function authoringSkills(doc = document) {
  try {
    const skills = JSON.parse(doc.getElementById("authoring-skills")?.textContent ?? "null");
    return Array.isArray(skills) ? skills.filter((s) => s && typeof s.name === "string") : [];
  } catch {
    return [];
  }
}

/** A command in words: {"skill": "go_to_goal", ...} -> "Go to goal: goal x 1 m, goal y 0.5 m". */
export function describeCommand(command, skills = []) {
  if (!command || typeof command !== "object") return t("No command");
  if (command.stop === true) return t("Stop the robot");
  if (command.sound) {
    const { frequency_hz: hz = 880, duration_s: seconds = 0.5, caption = "" } = command.sound;
    return t("Play a sound ({hz} Hz, {seconds} s), captioned “{caption}”", { hz: shortNumber(hz), seconds: shortNumber(seconds), caption });
  }
  if (command.drive) {
    const { linear_mps: linear = 0, angular_radps: angular = 0 } = command.drive;
    return t("Drive at {linear} m/s, turning {angular} rad/s", { linear: shortNumber(linear), angular: shortNumber(angular) });
  }
  const skill = skills.find((s) => s.name === command.skill);
  const schema = new Map((skill?.parameters ?? []).map((p) => [p.name, p]));
  const values = Object.entries(command.parameters ?? {}).map(([name, value]) => {
    const unit = schema.get(name)?.unit;
    return `${parameterLabel(name).toLowerCase()} ${typeof value === "number" ? shortNumber(value) : value}${unit ? ` ${unit}` : ""}`;
  });
  return `${skill?.title ?? parameterLabel(String(command.skill))}${values.length ? `: ${values.join(", ")}` : ""}`;
}

export class CommandBuilder {
  #skills;
  #kind;
  #skillSelect;
  #skillHelp;
  #parameterBox;
  #drive;
  #skillPart;
  #sound;
  #inputs = new Map();
  #id = `command-${++nextId}`;

  /** Fills container with the fields; optional adds "No command". */
  constructor(container, skills, { optional = false, legend = t("Command"), sounds = false } = {}) {
    this.#skills = skills.filter((skill) => !skill.direct_drive); // "Drive" is that skill, in fewer words
    const choices = [
      ...(optional ? [["none", t("No command")]] : []),
      ...(this.#skills.length ? [["skill", t("Run a skill")]] : []),
      ["drive", t("Drive")], ["stop", t("Stop the robot")],
      ...(sounds ? [["sound", t("Play a sound (the robot stands still)")]] : []),
    ];
    this.#kind = h("select", { id: `${this.#id}-kind`, "data-field": "command-kind" },
      choices.map(([value, text]) => h("option", { value, text })));
    this.#skillSelect = h("select", { id: `${this.#id}-skill`, "data-field": "command-skill" },
      this.#skills.map((skill) => h("option", { value: skill.name, text: skill.title || parameterLabel(skill.name) })));
    this.#skillHelp = h("p", { class: "muted small", "data-field": "command-skill-help" });
    this.#parameterBox = h("div", { class: "command-builder__parameters" });
    const number = (name, max, value, unit) => h("label", {}, `${parameterLabel(name)} [${unit}]`,
      h("input", { name, type: "number", step: "any", min: String(-max), max: String(max), value: String(value),
        inputmode: "decimal", "data-drive": name }));
    this.#drive = h("div", { class: "command-builder__drive", hidden: true },
      number("linear_mps", MAX_LINEAR_MPS, 0.2, "m/s"), number("angular_radps", MAX_ANGULAR_RADPS, 0, "rad/s"),
      h("p", { class: "muted small", text: t("Speeds up to {MAX_LINEAR_MPS} m/s and {MAX_ANGULAR_RADPS} rad/s; the ", { MAX_LINEAR_MPS, MAX_ANGULAR_RADPS })
        + t("robot drives until the cue or step ends.") }));
    this.#sound = h("div", { class: "command-builder__sound", hidden: true },
      h("label", {}, t("Pitch [Hz]"), h("input", { name: "frequency_hz", type: "number", step: "any", min: "100",
        max: "4000", value: "880", inputmode: "decimal", "data-sound": "frequency_hz" })),
      h("label", {}, t("Length [s]"), h("input", { name: "duration_s", type: "number", step: "any", min: "0.05",
        max: "5", value: "0.5", inputmode: "decimal", "data-sound": "duration_s" })),
      h("label", {}, t("Caption, shown to those who cannot hear it"), h("input", { name: "caption", maxlength: "120",
        value: t("The robot beeps"), "data-sound": "caption" })));
    const skillPart = h("div", { class: "command-builder__skill" },
      h("label", { for: this.#skillSelect.id, text: t("Skill") }), this.#skillSelect, this.#skillHelp, this.#parameterBox);
    container.append(h("fieldset", { class: "command-builder" },
      h("legend", { text: legend }),
      h("label", { for: this.#kind.id, text: t("What the robot does") }), this.#kind,
      skillPart, this.#drive, this.#sound));
    this.#kind.addEventListener("change", () => this.#show());
    this.#skillSelect.addEventListener("change", () => this.#buildParameters());
    this.#skillPart = skillPart;
    this.#buildParameters();
    this.#show();
  }

  /** The command as the server takes it, or null for "No command"; throws an Error naming the field. */
  value() {
    const kind = this.#kind.value;
    if (kind === "none") return null;
    if (kind === "stop") return { stop: true };
    if (kind === "sound") {
      const [hz, seconds, caption] = this.#sound.querySelectorAll("input");
      for (const input of [hz, seconds]) {
        if (!input.checkValidity() || input.value === "") throw this.#invalid(input, input.parentElement.firstChild.textContent);
      }
      if (!caption.value.trim()) {
        caption.focus();
        throw new Error("Caption: write what the sound is, for those who cannot hear it.");
      }
      return { sound: { frequency_hz: Number(hz.value), duration_s: Number(seconds.value), caption: caption.value.trim() } };
    }
    if (kind === "drive") {
      const drive = {};
      for (const input of this.#drive.querySelectorAll("input")) {
        if (!input.checkValidity() || input.value === "") throw this.#invalid(input, parameterLabel(input.name));
        drive[input.name] = Number(input.value);
      }
      return { drive };
    }
    const parameters = {};
    for (const [name, { parameter, input }] of this.#inputs) {
      if (!input.checkValidity()) throw this.#invalid(input, parameterLabel(name));
      const value = readValue(parameter, input);
      if (value !== undefined) parameters[name] = value;
    }
    return { skill: this.#skillSelect.value, parameters };
  }

  #invalid(input, label) {
    input.focus();
    const range = input.min && input.max ? t(" between {min} and {max}", { min: input.min, max: input.max }) : "";
    return new Error(`${label}: enter a number${range}.`);
  }

  #show() {
    const kind = this.#kind.value;
    this.#skillPart.hidden = kind !== "skill";
    this.#drive.hidden = kind !== "drive";
    this.#sound.hidden = kind !== "sound";
  }

  #buildParameters() {
    const skill = this.#skills.find((s) => s.name === this.#skillSelect.value);
    this.#skillHelp.textContent = skill?.help ?? "";
    this.#inputs.clear();
    this.#parameterBox.replaceChildren(...(skill?.parameters ?? []).map((parameter) => this.#field(parameter)));
  }

  #field(parameter) {
    const id = `${this.#id}-${parameter.name}`;
    const attrs = { id, name: parameter.name, "data-parameter": parameter.name };
    let input;
    if (parameter.type === "bool") {
      input = h("input", { ...attrs, type: "checkbox", checked: Boolean(parameter.default) });
    } else if (parameter.type === "enum") {
      input = h("select", attrs, (parameter.choices ?? []).map((choice) =>
        h("option", { value: String(choice), selected: choice === parameter.default, text: String(choice) })));
    } else if (parameter.type === "string") {
      input = h("input", { ...attrs, type: "text", value: parameter.default ?? "" });
    } else {
      const limited = Number.isFinite(parameter.minimum) && Number.isFinite(parameter.maximum)
        && (parameter.minimum || parameter.maximum);
      input = h("input", {
        ...attrs, type: "number", step: parameter.type === "int" ? "1" : "any", required: true,
        inputmode: parameter.type === "int" ? "numeric" : "decimal",
        min: limited ? String(parameter.minimum) : null, max: limited ? String(parameter.maximum) : null,
        value: parameter.default === undefined || parameter.default === null ? "" : String(parameter.default),
      });
    }
    this.#inputs.set(parameter.name, { parameter, input });
    const numeric = parameter.type === "double" || parameter.type === "int";
    const range = numeric && Number.isFinite(parameter.minimum) && Number.isFinite(parameter.maximum)
      && (parameter.minimum || parameter.maximum) ? t(" ({minimum} to {maximum})", { minimum: shortNumber(parameter.minimum), maximum: shortNumber(parameter.maximum) }) : "";
    return h("div", { class: "command-builder__field" },
      h("label", { for: id }, parameterLabel(parameter.name), parameter.unit ? ` [${parameter.unit}]` : ""),
      input,
      h("p", { class: "muted small", text: `${parameter.help ?? ""}${range}` }));
  }
}
