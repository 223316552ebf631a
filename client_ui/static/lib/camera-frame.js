// Decoding of the camera socket's binary frames, kept pure so it can be tested without a browser.
// Layout: 4-byte big-endian header length N, N bytes of UTF-8 JSON header, then the JPEG bytes.

const LENGTH_PREFIX_BYTES = 4;
const utf8 = new TextDecoder("utf-8", { fatal: true });

/**
 * Split one camera message into its header and JPEG bytes.
 *
 * @param {ArrayBuffer} buffer
 * @returns {{header: object, jpeg: Uint8Array}}
 * @throws {Error} when the message is truncated or the header is not a JSON object
 */
export function parseFramePacket(buffer) {
  if (!(buffer instanceof ArrayBuffer) || buffer.byteLength < LENGTH_PREFIX_BYTES) {
    throw new Error("camera frame is too short");
  }
  const headerLength = new DataView(buffer).getUint32(0, false);
  const jpegStart = LENGTH_PREFIX_BYTES + headerLength;
  if (jpegStart > buffer.byteLength) throw new Error("camera frame header runs past the end");
  const header = JSON.parse(utf8.decode(new Uint8Array(buffer, LENGTH_PREFIX_BYTES, headerLength)));
  if (header === null || typeof header !== "object" || Array.isArray(header)) {
    throw new Error("camera frame header is not an object");
  }
  return { header, jpeg: new Uint8Array(buffer, jpegStart) };
}

/** Frames drawn in the last `windowMs` before `nowMs`, i.e. frames per second for a 1 s window. */
export function framesInWindow(timestampsMs, nowMs, windowMs = 1000) {
  return timestampsMs.filter((t) => nowMs - t <= windowMs).length;
}
