// A small camera view for the teaching pages: frames from a camera channel into an <img> (latest wins).
import { Channel } from "../../lib/transport.js";
import { parseFramePacket } from "../../lib/camera-frame.js";

/** Shows the frames of the camera channel at path in img; returns the channel (close() it to stop). */
export function attachCamera(img, path) {
  const channel = new Channel(path, { binary: true });
  let url = null;
  channel.addEventListener("message", (event) => {
    if (!(event.detail instanceof ArrayBuffer)) return;
    let packet;
    try {
      packet = parseFramePacket(event.detail);
    } catch {
      return;
    }
    const next = URL.createObjectURL(new Blob([packet.jpeg], { type: "image/jpeg" }));
    img.src = next;
    if (url) URL.revokeObjectURL(url);
    url = next;
  });
  return channel;
}
