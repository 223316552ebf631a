// <plan-panel>: a saved plan used as a skill (issue 16, "Use as a skill"): its name, Run and Cancel, the line
// running and the end state. The console's "skill-goals" service runs it through the descriptor's run_url and
// follows its goal, as it does a skill's.
// In: `descriptor` ({plan_id, plan_name, skill, run_url, editor_url}), `goal` (a goal's state), `feedback`,
//     `goalEvent`, `error` ({code, message, field} or null).
// Out: "skill-activate" ({skill, parameters: {}, preempt: true}), "skill-cancel" ({skill, goal_id}).

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { t } from "../../lib/i18n.js";

const FINAL = new Set(["succeeded", "aborted", "canceled"]);

/** The plan line a goal's feedback names (values.line, else "line N: ..."), or null; pure. */
export function feedbackLine(feedback) {
  const value = Number(feedback?.values?.line);
  if (Number.isInteger(value) && value > 0) return value;
  const match = /^line (\d+)/.exec(feedback?.state ?? "");
  return match ? Number(match[1]) : null;
}

/** The words for a goal of a plan: "Running line 3: ...", "SUCCEEDED", "ABORTED at line 2 (CODE): ..."; pure. */
export function planGoalWords(goal, feedback = goal?.feedback) {
  if (!goal) return t("Not run yet.");
  const status = String(goal.status ?? "");
  if (!FINAL.has(status)) {
    const line = feedbackLine(feedback);
    return line ? t("Running line {line}: {value}", { line, value: String(feedback.state ?? "").replace(/^line \d+:\s*/, "") }) : t("Starting…");
  }
  if (status === "succeeded") return "SUCCEEDED";
  const message = String(goal.message ?? "");
  const line = /^line (\d+)/.exec(message)?.[1];
  const code = goal.error_code ? ` (${goal.error_code})` : "";
  return `${status.toUpperCase()}${line ? t(" at line {line}", { line }) : ""}${code}: ${message.replace(/^line \d+:\s*/, "")}`;
}

export class PlanPanel extends PanelElement {
  #descriptor = null;
  #goal = null;
  #status;
  #run;
  #cancel;
  #editor;

  build() {
    if (!this.#descriptor) return false;
    this.classList.add("panel");
    this.dataset.plan = String(this.#descriptor.plan_id);
    this.#run = h("button", { type: "button", class: "button button--primary", "data-action": "run-plan",
      text: t("Run") });
    this.#cancel = h("button", { type: "button", class: "button", "data-action": "cancel-plan", text: t("Cancel"),
      hidden: true });
    this.#run.addEventListener("click", () => {
      this.error = null;
      this.emit("skill-activate", { skill: this.#descriptor.skill, parameters: {}, preempt: true });
    });
    this.#cancel.addEventListener("click", () => {
      if (this.#goal) this.emit("skill-cancel", { skill: this.#descriptor.skill, goal_id: this.#goal.goal_id });
    });
    this.#editor = h("a", { href: this.#descriptor.editor_url, text: t("Open in the plan editor") });
    this.#status = h("p", { class: "plan-panel__status", "data-field": "plan-status", role: "status",
      "aria-live": "polite", text: t("Not run yet.") });
    this.append(
      h("h2", { class: "panel__title", text: t("Plan {value}", { value: this.#descriptor.plan_name }) }),
      h("div", { class: "plan-panel__actions" }, this.#run, this.#cancel, this.#editor),
      this.#status,
      this.messageLine({ class: "plan-panel__message", "data-field": "plan-message" }),
    );
    return true;
  }

  set descriptor(descriptor) {
    this.#descriptor = descriptor;
    this.ensureBuilt();
  }

  set goal(goal) {
    this.#goal = goal;
    this.#show(goal, goal?.feedback);
  }

  set feedback(feedback) {
    if (this.#goal) this.#show(this.#goal, feedback);
  }

  set goalEvent(_event) {}

  set error(error) {
    this.showMessage(error?.message ?? "");
  }

  #show(goal, feedback) {
    this.ensureBuilt();
    const ended = !goal || FINAL.has(goal.status);
    this.dataset.status = goal?.status ?? "";
    this.#status.textContent = planGoalWords(goal, feedback);
    this.#cancel.hidden = ended;
    this.#run.disabled = !ended;
  }
}

function checkPlanDescriptor(descriptor) {
  return descriptor?.plan_id && descriptor?.run_url && descriptor?.skill ? "" : t("a plan panel needs its plan");
}

export const register = registerPanel({
  kind: "plan", tag: "plan-panel", element: PlanPanel, stylesheets: [new URL("./plan-panel.css", import.meta.url)],
  feeds: [{ service: "skill-goals" }], check: checkPlanDescriptor,
});
