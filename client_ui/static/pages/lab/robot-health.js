// A robot's health page: reads /api/robots/<name>/health every two seconds and shows the loop, the process, the
// faults, the log's last lines and the maintenance log; the buttons ask the server for a recovery. It decides
// nothing: the server says who may act and what came of it.

import { ApiError, fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { DATE_LOCALE, fixed, t } from "../../lib/i18n.js";

const root = document.querySelector("#robot-health");
const POLL_MS = 2000;
const robot = root?.dataset.robot ?? "";
const api = `/api/robots/${encodeURIComponent(robot)}`;

function showError(text) {
  const line = root.querySelector("#health-error");
  line.textContent = text;
  line.hidden = !text;
}

function clock(unixSeconds) {
  return new Date(unixSeconds * 1000).toLocaleString(DATE_LOCALE, { dateStyle: "short", timeStyle: "medium" });
}

function duration(seconds) {
  const whole = Math.floor(seconds);
  const hours = Math.floor(whole / 3600);
  const minutes = Math.floor((whole % 3600) / 60);
  return hours ? `${hours} h ${minutes} min` : minutes ? `${minutes} min ${whole % 60} s` : `${whole} s`;
}

function figures(health) {
  const item = (label, value, field, warn = false) => h("div", {},
    h("dt", { text: label }), h("dd", { "data-field": field, "data-warn": String(warn), text: value }));
  const factor = health.parked ? t("{factor} (at rest)", { factor: fixed(health.real_time_factor, 2) })
    : fixed(health.real_time_factor, 2);
  return [
    item(t("Real-time factor"), factor, "real-time-factor", !health.parked && Math.abs(health.real_time_factor - 1) > 0.1),
    item(t("Loop lag (median / max)"), `${fixed(health.loop_lag_ms_p50, 1)} / ${fixed(health.loop_lag_ms_max, 1)} ms`,
      "loop-lag", health.loop_lag_ms_max > 100),
    item(t("CPU"), `${fixed(health.cpu_percent, 1)} %`, "cpu", health.cpu_percent > 90),
    item(t("Memory"), `${fixed(health.memory_mb, 0)} MB`, "memory"),
    item(t("Up for"), duration(health.uptime_s), "uptime"),
    item(t("Restarts"), String(health.restarts), "restarts"),
    item(t("Version"), health.version, "version"),
    item(t("Process"), String(health.pid), "pid"),
  ];
}

function show(data) {
  const health = data.health;
  root.querySelector('[data-field="online"]').textContent = health.online
    ? t("{robot} answers.", { robot }) : health.message;
  root.querySelector('[data-slot="figures"]').replaceChildren(...(health.online ? figures(health) : []));
  const faults = health.online ? health.faults.slice().reverse() : [];
  root.querySelector('[data-slot="faults"]').replaceChildren(...(faults.length ? faults.map((fault) =>
    h("li", { "data-kind": fault.kind }, h("time", { text: clock(fault.at_unix_s) }), fault.message))
    : [h("li", { class: "muted", text: health.online ? t("No fault since the robot started.") : "—" })]));
  root.querySelector('[data-slot="log"]').textContent = health.online ? health.log_tail.join("\n") || t("(empty)") : "—";
  root.querySelector('[data-action="restart"]').disabled = !(health.online && health.restartable);
  root.querySelector('[data-slot="maintenance"]').replaceChildren(...(data.maintenance.length
    ? data.maintenance.map((entry) => h("li", { "data-action": entry.action },
      h("time", { text: new Date(entry.at).toLocaleString(DATE_LOCALE, { dateStyle: "short", timeStyle: "medium" }) }),
      t("{actor}: {outcome}", { actor: entry.actor ?? t("a deleted account"), outcome: entry.outcome })))
    : [h("li", { class: "muted", text: t("Nothing done yet.") })]));
}

async function refresh() {
  try {
    show(await fetchJson(`${api}/health`));
    showError("");
  } catch (error) {
    showError(error instanceof ApiError ? error.message : t("The lab server could not be reached."));
  }
}

async function act(action) {
  const result = root.querySelector('[data-field="action-result"]');
  result.textContent = t("Working…");
  try {
    const answer = await fetchJson(`${api}/maintenance`, { method: "POST", body: { action } });
    result.textContent = answer.message;
    showError("");
  } catch (error) {
    result.textContent = "";
    showError(error instanceof ApiError ? error.message : t("The lab server could not be reached."));
  }
  await refresh();
}

if (root) {
  const confirmBox = root.querySelector('[data-slot="confirm"]');
  root.querySelector('[data-action="dock"]').addEventListener("click", () => act("dock"));
  root.querySelector('[data-action="clear_map"]').addEventListener("click", () => act("clear_map"));
  root.querySelector('[data-action="restart"]').addEventListener("click", () => {
    confirmBox.hidden = false;
    confirmBox.querySelector('[data-action="confirm-restart"]').focus();
  });
  confirmBox.querySelector('[data-action="cancel-restart"]').addEventListener("click", () => { confirmBox.hidden = true; });
  confirmBox.querySelector('[data-action="confirm-restart"]').addEventListener("click", () => {
    confirmBox.hidden = true;
    act("restart");
  });
  refresh();
  setInterval(refresh, POLL_MS);
}
