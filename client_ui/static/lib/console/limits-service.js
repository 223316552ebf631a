// The low-level settings' feed service ("limits", registered in feed-services.js): the robot's velocity ceilings and
// watchdog, read once the console starts and again whenever control changes hands (the robot then resets them),
// changed when the panel asks. It needs only the wiring's public side, as any feed service in its own module.

import { fetchJson } from "../transport.js";
import { registerFeedService } from "./feed-services.js";
import { t } from "../i18n.js";

function problem(error, prefix = "") {
  return { code: error.code ?? "network", message: `${prefix}${error.message}`, field: error.field ?? null };
}

/** Connects a low-level panel to GET/POST /api/robots/<r>/limits. */
export function connectLimits(wiring, descriptor, panel) {
  const url = `/api/robots/${encodeURIComponent(wiring.robotName)}/limits`;
  panel.addEventListener("limits-change", async ({ detail }) => {
    try {
      panel.limits = await fetchJson(url, { method: "POST", body: detail });
    } catch (error) {
      panel.error = problem(error);
    }
  });
  const load = async () => {
    try {
      panel.limits = await fetchJson(url);
    } catch (error) {
      panel.error = { ...problem(error, t("The limits could not be read: ")), field: null };
    }
  };
  const queuePath = `${wiring.robotPath}/queue`;
  if (wiring.hasChannel(queuePath)) { // the turn panel's socket, never one of its own (opening it joins the queue)
    let controlling = null;
    wiring.listen(queuePath, descriptor.id, (message) => {
      if (message.type !== "queue" || message.is_controller === controlling) return;
      controlling = message.is_controller;
      panel.observing = !controlling;
      load();
    });
  }
  wiring.onStart(load);
}

registerFeedService("limits", connectLimits);
