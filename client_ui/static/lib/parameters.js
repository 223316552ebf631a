// Skill parameters for people, shared by the skill panels and the authoring forms: labels, typed values, limits.

import { number, t } from "./i18n.js";

/** "goal_x_m" -> "Goal x"; the unit is shown apart. */
export function parameterLabel(name) {
  const words = String(name).replace(/_(m|mps|rad|radps|s|deg|ms)$/, "").split("_").filter(Boolean);
  const text = words.join(" ");
  return text ? t(text[0].toUpperCase() + text.slice(1)) : String(name);  // the robot's labels: robot_words.py
}

/** The value an input holds, typed by the parameter's schema; undefined when empty. */
export function readValue(parameter, input) {
  if (parameter.type === "bool") return input.checked;
  if (input.value === "") return undefined;
  if (parameter.type === "double") return Number(input.value);
  if (parameter.type === "int") return Number.parseInt(input.value, 10);
  return input.value;
}

/** A limit for people: 3.141592653589793 -> "3.142" ("3,142" in Spanish). */
export function shortNumber(value) {
  const rounded = Number(Number(value).toPrecision(4)) + 0; // data, not text: rounds as before; number() writes it
  return number(rounded, { maximumFractionDigits: 20, useGrouping: false });
}

