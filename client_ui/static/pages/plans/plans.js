// The plans page: my plans and those shared with my courses, a new plan, and a plan file imported.
import { ApiError, fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { t } from "../../lib/i18n.js";

const STARTER_TEXT = '# A first plan: one command a line.\nsay "Hello"\ndrive 0.2 0 for 2s\n';
const mine = document.querySelector("[data-slot=mine]");
const shared = document.querySelector("[data-slot=shared]");

function planItem(plan) {
  const details = plan.mine
    ? (plan.shared_with ? t("shared with {code}", { code: plan.shared_with.code }) : t("private"))
    : t("by {owner}, shared with {value}", { owner: plan.owner, value: plan.shared_with?.code ?? t("you") });
  return h("li", { class: "plans-list__item", "data-plan-id": plan.id },
    h("a", { href: `/plans/${plan.id}`, class: "plans-list__name" }, plan.name),
    h("span", { class: "muted small" }, t(" version {latest_version}, {details}", { latest_version: plan.latest_version, details })));
}

function fill(list, plans, empty) {
  list.replaceChildren(...(plans.length ? plans.map(planItem) : [h("li", { class: "muted" }, empty)]));
}

async function load() {
  try {
    const { plans } = await fetchJson("/api/plans");
    fill(mine, plans.filter((p) => p.mine), t("No plans yet: create one below."));
    fill(shared, plans.filter((p) => !p.mine), t("No plan is shared with your courses."));
  } catch (error) {
    mine.replaceChildren(h("li", { class: "plans-message--error" }, error.message));
  }
}

function showErrors(list, error) {
  const errors = error?.payload?.errors ?? [];
  list.replaceChildren(...errors.map((e) => h("li", {}, e.message)));
}

document.getElementById("new-plan").addEventListener("submit", async (event) => {
  event.preventDefault();
  const form = event.currentTarget;
  const message = form.querySelector("[data-field=new-message]");
  message.textContent = t("Creating…");
  try {
    const { plan } = await fetchJson("/api/plans", { method: "POST",
      body: { name: form.elements.name.value.trim(), text: STARTER_TEXT } });
    window.location.assign(`/plans/${plan.id}`);
  } catch (error) {
    message.textContent = error.message;
    form.elements.name.setAttribute("aria-invalid", String(error.field === "name"));
  }
});

document.getElementById("import-plan").addEventListener("submit", async (event) => {
  event.preventDefault();
  const form = event.currentTarget;
  const message = form.querySelector("[data-field=import-message]");
  const errors = form.querySelector("[data-slot=import-errors]");
  errors.replaceChildren();
  if (!form.elements.file.files.length) {
    message.textContent = t("Choose a plan file (.json or .txt) to import.");
    return;
  }
  message.textContent = t("Importing…");
  const data = new FormData(form);
  try {
    const response = await fetch("/api/plans/import", { method: "POST", body: data, credentials: "same-origin",
      headers: { Accept: "application/json",
                 "X-CSRFToken": document.querySelector('meta[name="csrf-token"]')?.content ?? "" } });
    const payload = await response.json().catch(() => null);
    if (!response.ok) {
      const error = payload?.error ?? {};
      throw new ApiError(response.status, error.code, error.message ?? t("The file was not imported."), error.field,
        payload);
    }
    window.location.assign(`/plans/${payload.plan.id}`);
  } catch (error) {
    message.textContent = error.message;
    showErrors(errors, error);
  }
});

load();
