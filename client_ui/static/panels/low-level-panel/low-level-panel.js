// <low-level-panel>: the robot's low-level commands: its battery, and the velocity ceilings and watchdog (deadman)
// timeout in force, with inputs for the ones this user may change (the server says which: role and course).
// In: `telemetry` (a {"type": "telemetry", battery: {charge, charging, empty}} message), `message` (status/error
//     JSON of the socket), `limits` ({limits: {...}, may_change: [...], message?}: the API's answer),
//     `error` ({code, message, field} or null: a refusal, shown next to its field), `observing` (true while someone
//     else has the turn: the inputs are read-only, as the server would refuse them).
// Out: "limits-change" (detail {field: value, ...}: only the fields the person filled in).
// The server checks every value (range, permission, control); the browser only sends what was typed.

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { fixed as localFixed, t } from "../../lib/i18n.js";

const SETTINGS = [
  { name: "max_linear_mps", label: t("Max speed"), unit: "m/s", decimals: 2, low: () => 0, high: (l) => l.robot_max_linear_mps },
  { name: "max_angular_radps", label: t("Max turn rate"), unit: "rad/s", decimals: 2, low: () => 0,
    high: (l) => l.robot_max_angular_radps },
  { name: "watchdog_s", label: t("Watchdog timeout"), unit: "s", decimals: 1, low: (l) => l.min_watchdog_s,
    high: (l) => l.max_watchdog_s },
];
const LOW_CHARGE = 0.2;

/** The battery's words for people; pure. */
export function batteryWords(battery) {
  if (!battery || !Number.isFinite(Number(battery.charge))) return "—";
  const percent = `${Math.round(Number(battery.charge) * 100)} %`;
  if (battery.empty) return t("{percent}: empty. The robot will not move until it is back at its dock.", { percent });
  if (battery.charging) return t("{percent}: charging at the dock.", { percent });
  if (Number(battery.charge) < LOW_CHARGE) return t("{percent}: low. Return to the dock soon.", { percent });
  return percent;
}

function fixed(value, decimals) {
  const number = Number(value);
  return Number.isFinite(number) ? localFixed(number, decimals) : "—";
}

let panelCount = 0;

export class LowLevelPanel extends PanelElement {
  #uid = `low-level-${(panelCount += 1)}`;
  #meter;
  #batteryText;
  #form;
  #inputs = new Map();     // name -> input
  #current = new Map();    // name -> element showing the value in force
  #notes = new Map();      // name -> "not yours to change" note
  #errors = new Map();     // name -> error line
  #formError;
  #answer;
  #save;
  #observingNote;
  #mayChange = new Set();
  #observing = false;

  build() {
    this.classList.add("panel");
    this.#meter = h("meter", { min: "0", max: "1", low: String(LOW_CHARGE), high: "0.5", optimum: "1", value: "0",
      "data-field": "battery-meter", "aria-labelledby": `${this.#uid}-battery-label` });
    this.#batteryText = h("span", { class: "low-level__battery-text", "data-field": "battery", text: "—" });
    this.#form = h("form", { class: "low-level__form", novalidate: true, "aria-describedby": `${this.#uid}-help` },
      SETTINGS.map((setting) => this.#field(setting)),
      this.#formError = h("p", { class: "low-level__error", "data-field": "limits-error", role: "alert", hidden: true }),
      h("div", { class: "low-level__actions" },
        this.#save = h("button", { type: "submit", class: "button button--primary", "data-action": "save-limits",
          text: t("Save") }),
        this.#observingNote = h("span", { class: "low-level__note", "data-field": "limits-observing", hidden: true,
          text: t("You are observing: the settings are the controller's to change.") })));
    this.#form.addEventListener("submit", (event) => {
      event.preventDefault();
      this.#submit();
    });
    this.append(
      h("h2", { class: "panel__title", text: t("Low-level commands") }),
      h("div", { class: "low-level__battery" },
        h("span", { class: "low-level__label", id: `${this.#uid}-battery-label`, text: t("Battery") }),
        this.#meter, this.#batteryText),
      h("p", { class: "low-level__help", id: `${this.#uid}-help`,
        text: t("Ceilings for every motion (drive pad, skills, plans) and how long the robot keeps driving when your commands stop arriving. Leave a field empty to keep its value; they reset when the turn passes.") }),
      this.#form,
      this.#answer = h("p", { class: "low-level__answer", "data-field": "limits-answer", role: "status" }),
      this.messageLine({ class: "low-level__message", "data-field": "low-level-message" }),
    );
  }

  #field(setting) {
    const id = `${this.#uid}-${setting.name}`;
    const input = h("input", { id, name: setting.name, type: "number", step: "any", inputmode: "decimal",
      disabled: true, "aria-describedby": `${id}-now ${id}-error` });
    const current = h("span", { id: `${id}-now`, class: "low-level__now", "data-current": setting.name, text: "—" });
    const note = h("span", { class: "low-level__note", text: t("Not yours to change in this course."), hidden: true });
    const error = h("p", { id: `${id}-error`, class: "low-level__field-error", "data-field-error": setting.name,
      hidden: true });
    this.#inputs.set(setting.name, input);
    this.#current.set(setting.name, current);
    this.#notes.set(setting.name, note);
    this.#errors.set(setting.name, error);
    return h("div", { class: "low-level__field" },
      h("label", { for: id }, setting.label, " ", h("span", { class: "low-level__unit", text: `(${setting.unit})` })),
      input,
      h("span", { class: "low-level__hint" }, t("now "), current, " ", setting.unit, " ", note),
      error);
  }

  #submit() {
    this.#clearErrors();
    const detail = {};
    for (const [name, input] of this.#inputs) {
      if (input.disabled || input.value.trim() === "") continue;
      const value = Number(input.value);
      detail[name] = Number.isFinite(value) ? value : input.value; // the server names what is wrong
    }
    if (Object.keys(detail).length === 0) {
      this.#showFormError(t("Type a new value in at least one field first."));
      return;
    }
    this.#answer.textContent = t("Saving…");
    this.emit("limits-change", detail);
  }

  #clearErrors() {
    for (const [name, line] of this.#errors) {
      line.hidden = true;
      line.textContent = "";
      this.#inputs.get(name).removeAttribute("aria-invalid");
    }
    this.#formError.hidden = true;
    this.#formError.textContent = "";
  }

  #showFormError(text) {
    this.#formError.textContent = text;
    this.#formError.hidden = false;
  }

  /** The API's answer: the limits in force, what this user may change, and the sentence of a save. */
  set limits(answer) {
    this.ensureBuilt();
    const limits = answer?.limits ?? {};
    const mayChange = new Set(Array.isArray(answer?.may_change) ? answer.may_change : []);
    for (const setting of SETTINGS) {
      const input = this.#inputs.get(setting.name);
      this.#current.get(setting.name).textContent = fixed(limits[setting.name], setting.decimals);
      const low = Number(setting.low(limits));
      const high = Number(setting.high(limits));
      if (Number.isFinite(low)) input.min = String(low);
      if (Number.isFinite(high)) input.max = String(high);
      input.placeholder = fixed(limits[setting.name], setting.decimals);
      this.#notes.get(setting.name).hidden = mayChange.has(setting.name);
      if (answer?.message) input.value = "";
    }
    this.#mayChange = mayChange;
    this.#applyAccess();
    this.#clearErrors();
    this.#answer.textContent = answer?.message ?? "";
  }

  /** True while someone else has the turn. */
  set observing(observing) {
    this.ensureBuilt();
    this.#observing = Boolean(observing);
    this.#applyAccess();
  }

  #applyAccess() {
    for (const [name, input] of this.#inputs) input.disabled = this.#observing || !this.#mayChange.has(name);
    this.#save.disabled = this.#observing || this.#mayChange.size === 0;
    this.#observingNote.hidden = !this.#observing;
  }

  /** A refusal: next to its field when it names one of them, else under the form. */
  set error(error) {
    this.ensureBuilt();
    this.#clearErrors();
    this.#answer.textContent = "";
    if (!error) return;
    const line = this.#errors.get(error.field);
    if (line) {
      line.textContent = error.message;
      line.hidden = false;
      this.#inputs.get(error.field).setAttribute("aria-invalid", "true");
      this.#inputs.get(error.field).focus();
    } else {
      this.#showFormError(error.message);
    }
  }

  /** A telemetry message: the battery figure. */
  set telemetry(message) {
    this.ensureBuilt();
    const battery = message?.battery;
    const charge = Number(battery?.charge);
    if (Number.isFinite(charge)) this.#meter.value = Math.max(0, Math.min(1, charge));
    this.#batteryText.textContent = batteryWords(battery);
    this.dataset.battery = battery?.empty ? "empty" : battery?.charging ? "charging" : "";
    this.showMessage("");
  }
}

export const register = registerPanel({
  kind: "low-level", tag: "low-level-panel", element: LowLevelPanel,
  stylesheets: [new URL("./low-level-panel.css", import.meta.url)],
  feeds: [
    { socket: "telemetry", messages: { telemetry: "telemetry", status: "message", error: "message" } },
    { service: "limits" },
  ],
});
