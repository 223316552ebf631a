// The views drawn in the browser's feed service ("scene"): the robot's static world (GET /api/robots/<r>/scene),
// read once the console starts (the browser keeps it by its version, the ETag, and asks again only to confirm),
// tried again while the robot does not answer, and read again when the wiring's "obstacles-withheld" says an
// obstacle-zone test began (the camera was refused), so the views drawn here drop the obstacles too.

import { fetchJson } from "../transport.js";
import { registerFeedService } from "./feed-services.js";
import { t } from "../i18n.js";

const SCENE_RETRY_MS = 5000;

/** Connects a scene-drawing panel to the robot's scene. */
export function connectScene(wiring, descriptor, panel) {
  const load = async () => {
    try {
      const scene = await fetchJson(`/api/robots/${encodeURIComponent(wiring.robotName)}/scene`);
      panel.note = String(scene?.obstacles_hidden ?? ""); // the obstacles left out during an obstacle-zone test
      wiring.guard(descriptor.id, () => { panel.scene = scene; });
    } catch (error) {
      panel.note = t("The lab's description could not be loaded: {message}", { message: error.message });
      if (error.status === 503 || error.status === 0) setTimeout(load, SCENE_RETRY_MS);
    }
  };
  wiring.onStart(load);
  wiring.addEventListener("obstacles-withheld", load);
}

registerFeedService("scene", connectScene);
