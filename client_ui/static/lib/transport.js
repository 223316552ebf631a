// The one place that talks to the server: JSON over fetch, and channels that reconnect, on one WebSocket a page.
// Everything the server says is data to show; nothing here decides what the user may do.
import { PageLink } from "./page-link.js";
import { t } from "./i18n.js";

/** Close codes after which trying again cannot help. */
export const CLOSE_CODES = Object.freeze({
  NOT_LOGGED_IN: 4401,
  NOT_ALLOWED: 4403,
  UNKNOWN_ROBOT: 4404,
});
const FINAL_CLOSE_CODES = new Set(Object.values(CLOSE_CODES));
const NORMAL_CLOSURE = 1000;

/**
 * An error answer from the JSON API: `{"error": {"code", "message", "field"}}`; `payload` is the whole body
 * (some answers add to it, e.g. a lesson's errors by line); status 0 means the server could not be reached.
 */
export class ApiError extends Error {
  constructor(status, code, message, field = null, payload = null) {
    super(message);
    this.name = "ApiError";
    this.status = status;
    this.code = code;
    this.field = field;
    this.payload = payload;
  }
}

function csrfToken() {
  return document.querySelector('meta[name="csrf-token"]')?.content ?? "";
}

/** Fetch JSON from the same origin; resolves to the body, rejects with ApiError. */
export async function fetchJson(url, { method = "GET", body, signal } = {}) {
  const headers = { Accept: "application/json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  if (method !== "GET" && method !== "HEAD") headers["X-CSRFToken"] = csrfToken();

  let response;
  try {
    response = await fetch(url, {
      method,
      headers,
      body: body === undefined ? undefined : JSON.stringify(body),
      credentials: "same-origin",
      signal,
    });
  } catch (networkError) {
    if (networkError.name === "AbortError") throw networkError;
    throw new ApiError(0, "network", t("The lab server cannot be reached. Check your connection and try again."));
  }

  const payload = await response.json().catch(() => null);
  if (!response.ok) {
    const error = payload?.error;
    throw new ApiError(
      response.status,
      error?.code ?? "http_" + response.status,
      error?.message ?? t("The server answered {status} {statusText}.", { status: response.status, statusText: response.statusText }),
      error?.field ?? null,
      payload,
    );
  }
  return payload;
}

/**
 * A POST whose answer is a stream of JSON lines (application/x-ndjson): onMessage(message) for each line as it
 * comes; resolves when the stream ends. A refusal before the stream is thrown as fetchJson throws it; aborting
 * signal closes the stream (the server then stops what it was doing for this request).
 */
export async function fetchJsonLines(url, { body, signal } = {}, onMessage = () => {}) {
  let response;
  try {
    response = await fetch(url, {
      method: "POST",
      headers: { Accept: "application/x-ndjson", "Content-Type": "application/json", "X-CSRFToken": csrfToken() },
      body: JSON.stringify(body ?? {}),
      credentials: "same-origin",
      signal,
    });
  } catch (networkError) {
    if (networkError.name === "AbortError") throw networkError;
    throw new ApiError(0, "network", t("The lab server cannot be reached. Check your connection and try again."));
  }
  if (!response.ok || !response.body) {
    const payload = await response.json().catch(() => null);
    const error = payload?.error;
    throw new ApiError(response.status, error?.code ?? "http_" + response.status,
      error?.message ?? t("The server answered {status} {statusText}.", { status: response.status, statusText: response.statusText }), error?.field ?? null, payload);
  }
  const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
  let pending = "";
  for (;;) {
    let chunk;
    try {
      chunk = await reader.read();
    } catch (streamError) {
      if (streamError.name === "AbortError") throw streamError;
      throw new ApiError(0, "network", t("The connection to the lab server was lost before the answer ended."));
    }
    if (chunk.done) break;
    pending += chunk.value;
    const lines = pending.split("\n");
    pending = lines.pop();
    for (const line of lines) {
      const message = parseJsonMessage(line);
      if (message) onMessage(message);
    }
  }
  const last = parseJsonMessage(pending);
  if (last) onMessage(last);
}

/** ws:// or wss:// URL for a same-origin path, matching how the page was loaded. */
export function socketUrl(path) {
  const scheme = location.protocol === "https:" ? "wss:" : "ws:";
  return `${scheme}//${location.host}${path}`;
}

/** Delay before reconnect attempt `attempt` (0-based): exponential, capped, with jitter. */
export function backoffDelayMs(attempt, { baseMs = 500, capMs = 15000, random = Math.random } = {}) {
  const ceiling = Math.min(capMs, baseMs * 2 ** attempt);
  // Jitter keeps a room full of consoles from reconnecting in lock-step after a server restart.
  return Math.round(ceiling * (0.5 + random() * 0.5));
}

/**
 * A channel (a server path under /ws/) that reconnects with backoff until closed or refused for good. It rides
 * on the page's one WebSocket (page-link.js) unless `own` asks for a socket of its own.
 *
 * Events: "statechange" (detail: the state object), "open" (a fresh channel is ready; re-subscribe
 * here), "message" (detail: string or ArrayBuffer).
 * State: { phase: "connecting"|"open"|"reconnecting"|"closed", code, reason, retryAt, attempt }.
 */
export class Channel extends EventTarget {
  #path;
  #own;
  #carrier = null;
  #attempt = 0;
  #retryTimer = 0;
  #stableTimer = 0;
  #stopped = false;
  #state = { phase: "connecting", code: null, reason: "", retryAt: null, attempt: 0 };

  constructor(path, { binary = false, stableAfterMs = 3000, own = false } = {}) {
    super();
    this.#path = path;
    this.#own = own;
    this.binary = binary;
    this.stableAfterMs = stableAfterMs;
    this.#connect();
  }

  get state() {
    return this.#state;
  }

  get isOpen() {
    return this.#carrier?.isOpen ?? false;
  }

  /** Send a JSON-serialisable value; returns false when the channel is not open. */
  sendJson(value) {
    if (!this.isOpen) return false;
    this.#carrier.send(JSON.stringify(value));
    return true;
  }

  /** Close for good (no reconnect). */
  close(reason = "closed by the page") {
    this.#stopped = true;
    clearTimeout(this.#retryTimer);
    clearTimeout(this.#stableTimer);
    this.#carrier?.close(NORMAL_CLOSURE, reason);
    this.#setState({ phase: "closed", code: NORMAL_CLOSURE, reason, retryAt: null });
  }

  /** Skip the remaining backoff wait, e.g. when the browser comes back online. */
  retryNow() {
    if (this.#state.phase !== "reconnecting") return;
    clearTimeout(this.#retryTimer);
    this.#connect();
  }

  #setState(changes) {
    this.#state = { ...this.#state, ...changes, attempt: this.#attempt };
    this.dispatchEvent(new CustomEvent("statechange", { detail: this.#state }));
  }

  #connect() {
    this.#setState({ phase: "connecting", retryAt: null });
    let carrier = null;
    const current = () => this.#carrier === carrier && !this.#stopped;
    const on = {
      open: () => {
        if (!current()) return;
        // A server that accepts and then drops us at once must not earn a fast retry loop,
        // so the backoff resets only once the channel has stayed up for a while.
        this.#stableTimer = setTimeout(() => { this.#attempt = 0; }, this.stableAfterMs);
        this.#setState({ phase: "open", code: null, reason: "" });
        this.dispatchEvent(new Event("open"));
      },
      message: (data) => {
        if (current()) this.dispatchEvent(new CustomEvent("message", { detail: data }));
      },
      close: (code, reason) => {
        clearTimeout(this.#stableTimer);
        if (!current()) return;
        this.#carrier = null;
        if (FINAL_CLOSE_CODES.has(code)) {
          this.#stopped = true;
          this.#setState({ phase: "closed", code, reason, retryAt: null });
          return;
        }
        const delayMs = backoffDelayMs(this.#attempt);
        this.#attempt += 1;
        this.#setState({ phase: "reconnecting", code, reason, retryAt: Date.now() + delayMs });
        this.#retryTimer = setTimeout(() => this.#connect(), delayMs);
      },
    };
    carrier = this.#own ? new OwnSocket(socketUrl(this.#path), this.binary, on) : pageLink().carry(this.#path, on);
    this.#carrier = carrier;
  }
}

/** A channel's own WebSocket (the carrier of `new Channel(path, { own: true })`). */
class OwnSocket {
  #socket;

  constructor(url, binary, on) {
    const socket = new WebSocket(url);
    if (binary) socket.binaryType = "arraybuffer";
    socket.addEventListener("open", () => on.open());
    socket.addEventListener("message", (event) => on.message(event.data));
    socket.addEventListener("close", (event) => on.close(event.code, event.reason));
    this.#socket = socket;
  }

  get isOpen() {
    return this.#socket.readyState === WebSocket.OPEN;
  }

  send(text) {
    this.#socket.send(text);
  }

  close(code, reason) {
    if (this.#socket.readyState <= WebSocket.OPEN) this.#socket.close(code, reason);
  }
}

let theLink = null;

/** The page's link, made on first use. */
function pageLink() {
  theLink ??= new PageLink(socketUrl("/ws/link"));
  return theLink;
}

/** Parse a text frame as JSON; returns null (not throws) for anything that is not an object. */
export function parseJsonMessage(text) {
  try {
    const value = JSON.parse(text);
    return value !== null && typeof value === "object" ? value : null;
  } catch {
    return null;
  }
}
