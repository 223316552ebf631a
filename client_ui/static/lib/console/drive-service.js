// The drive pads' feed service ("drive"): one drive session per console (lib/drive-session.js) on the robot's drive
// socket, shared by every pad, timed for the response-times panel. The session's "ready" and "sent" go out on the
// wiring as "drive-ready" and "drive-sent" (the camera's motion preview follows them); a pad observes while the
// queue's "seat" says someone else controls the robot.

import { DriveSession } from "../drive-session.js";
import { perConsole, registerFeedService } from "./feed-services.js";
import { timeDriveCommands } from "./timing-wiring.js";

const driveOf = perConsole(() => ({ channel: null, session: null }));

/** The console's drive session on the socket at path, opened by its first pad. */
function ensureDrive(wiring, path) {
  const drive = driveOf(wiring);
  if (drive.session) return drive;
  drive.channel = wiring.channel(path);
  drive.session = new DriveSession(drive.channel);
  timeDriveCommands(drive.session, wiring.timings);
  for (const type of ["ready", "sent"]) {
    drive.session.addEventListener(type, ({ detail }) => {
      wiring.dispatchEvent(new CustomEvent(`drive-${type}`, { detail }));
    });
  }
  return drive;
}

/** Connects a drive pad: its commands go on the session, the session's answers and the link's state come back. */
export function connectDrivePad(wiring, descriptor, pad) {
  pad.link = "connecting";
  const { channel, session } = ensureDrive(wiring, descriptor.channel ?? `${wiring.robotPath}/drive`);
  session.addEventListener("ready", ({ detail }) => {
    pad.limits = { max_linear_mps: detail.max_linear_mps, max_angular_radps: detail.max_angular_radps };
    pad.link = "ready";
  });
  session.addEventListener("ack", ({ detail }) => { pad.ack = detail; });
  session.addEventListener("error", ({ detail }) => { pad.error = detail; });
  session.addEventListener("status", ({ detail }) => { if (detail.message) pad.error = detail; });
  channel.addEventListener("statechange", ({ detail }) => {
    if (detail.phase !== "open") pad.link = detail.phase === "closed" ? "closed" : "connecting";
  });
  pad.addEventListener("drive-command", ({ detail }) => session.setCommand(detail));
  pad.addEventListener("drive-stop", () => session.stop());
  wiring.addEventListener("seat", ({ detail }) => { pad.observing = !detail.is_controller; });
}

registerFeedService("drive", connectDrivePad);
