// The camera panel's feed service ("camera-stream"): the robot's binary camera socket, opened only while the panel
// shows the video (a picture drawn by this browser closes it: a robot nobody watches renders nothing), the person's
// picture and motion-preview choices (feedback-wiring.js), and the drive session's messages from the wiring's
// "drive-ready" / "drive-sent" for the motion preview. A camera refused for the viewer's obstacle-zone test says so
// on the connection line and sends "obstacles-withheld" on the wiring (the scene and the robot's description are
// read again without the obstacles).

import { parseJsonMessage } from "../transport.js";
import { registerFeedService } from "./feed-services.js";
import { bindFeedback, savePictureChoice } from "./feedback-wiring.js";
import { t } from "../i18n.js";

const DRAWN_PICTURE_STATUS = t("video off: picture drawn by this browser from where the robot stands");
const WITHHELD_CAMERA_STATUS = { phase: "off", reason: t("off during your obstacle-zone test (it would show the obstacles)") };

/** The picture first shown: this person's last choice for robots of this kind, else the admin's default. */
function firstPicture(descriptor) {
  const chosen = descriptor.picture?.chosen;
  if (chosen === "video" || chosen === "drawn") return chosen;
  return descriptor.picture?.default === "drawn" ? "drawn" : "video";
}

/** Opens the camera socket at path for panel; returns the channel. */
function openCamera(wiring, descriptor, panel, path, isCurrent) {
  const camera = wiring.channel(path, { binary: true });
  let withheld = false; // refused during the viewer's obstacle-zone test: on purpose, not a fault
  camera.addEventListener("statechange", ({ detail }) => {
    if (isCurrent(camera)) panel.connected = detail.phase === "open";
    if (withheld && detail.phase === "closed") wiring.status.update(path.split("/").pop(), WITHHELD_CAMERA_STATUS);
  });
  camera.addEventListener("message", ({ detail }) => {
    if (detail instanceof ArrayBuffer) {
      panel.frame = detail;
      return;
    }
    const message = parseJsonMessage(detail);
    if (!message) wiring.layout.notify(descriptor.id, t("Ignored a message that could not be read."));
    else if (message.type === "status" || message.type === "error") wiring.guard(descriptor.id, () => { panel.message = message; });
    if (message?.type === "error" && message.code === "obstacles_hidden" && !withheld) {
      withheld = true;
      wiring.dispatchEvent(new Event("obstacles-withheld"));
    }
    if (message?.type === "status" && typeof message.robot_online === "boolean") wiring.showOnline(message.robot_online);
  });
  return camera;
}

/** Connects a camera panel: the video while it is the chosen picture, the preferences, the drive session. */
export function connectCamera(wiring, descriptor, panel) {
  panel.robotName = wiring.robotName;
  bindFeedback(panel);
  wiring.addEventListener("drive-ready", ({ detail }) => { panel.driveReady = detail; });
  wiring.addEventListener("drive-sent", ({ detail }) => { panel.driveSent = detail; });
  const path = descriptor.channel ?? `${wiring.robotPath}/camera`;
  const name = path.split("/").pop();
  let current = null;
  const open = () => { current = openCamera(wiring, descriptor, panel, path, (camera) => camera === current); };
  const kind = descriptor.picture?.kind ?? wiring.robotName;
  const initial = firstPicture(descriptor);
  panel.source = initial;
  if (initial === "drawn") wiring.status.update(name, { phase: "off", reason: DRAWN_PICTURE_STATUS });
  else open();
  panel.addEventListener("camera-source-change", ({ detail }) => {
    if (!detail.fallback) savePictureChoice(kind, detail.source); // not a choice: this browser cannot draw
    if (detail.source === "drawn" && current) {
      current = null;
      const reason = "the picture is drawn by this browser"; // the close's reason, for the server's log
      wiring.closeChannel(path, reason);
      // Closed on purpose, not a fault: the line says where the picture comes from instead, without alarm.
      wiring.status.update(name, { phase: "off", reason: DRAWN_PICTURE_STATUS });
    } else if (detail.source === "video" && !current) {
      open();
    }
  });
}

registerFeedService("camera-stream", connectCamera);
