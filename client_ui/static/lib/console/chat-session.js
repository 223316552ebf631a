// Wires a <chat-panel> to the robot's chat socket: history on every (re)connect, then new messages,
// deletions and errors; the panel's chat-send / chat-delete events become socket commands.
// Each line the person writes stays in an outbox, shown as sending, until the server answers it (by the line's key).
// A leaving worker answers every line it has read before it closes with 1012, so a line still unanswered at a 1012
// was never read: it goes again on the next channel and is stored once. After any other close nobody knows whether
// the line was stored, so it waits, marked not sent, for the person to send it again.
// It registers the console's "chat" feed service (feed-services.js).

import { Channel, parseJsonMessage } from "../transport.js";
import { registerFeedService } from "./feed-services.js";

const SERVICE_RESTART = 1012; // middleware/live/codes.py CLOSE_SERVICE_RESTART

let lineCount = 0;

/** A key for one line, unique on this page (the server echoes it in its answer). */
function newLineKey() {
  lineCount += 1;
  return `${Date.now().toString(36)}-${lineCount}-${Math.random().toString(36).slice(2, 8)}`;
}

/** Lines written and not yet answered: line key -> {line, body, state: "sending" | "unsent", out}. */
class ChatOutbox {
  #chat;
  #panel;
  #lines = new Map();

  constructor(chat, panel) {
    this.#chat = chat;
    this.#panel = panel;
  }

  write(body) {
    const entry = { line: newLineKey(), body, state: "sending", out: false };
    this.#lines.set(entry.line, entry);
    this.#send(entry);
  }

  sendAgain(line) {
    const entry = this.#lines.get(line);
    if (entry && entry.state === "unsent") this.#send(entry);
  }

  /** The server stored or refused a line; true when the answer was one of ours. */
  answered(line, storedId) {
    const entry = this.#lines.get(line);
    if (!entry) return false;
    this.#lines.delete(line);
    if (storedId === null) this.#panel.withdrawn = { line, body: entry.body };
    else this.#panel.acknowledged = { line, id: storedId };
    return true;
  }

  opened() {
    for (const entry of this.#lines.values()) if (entry.state === "sending" && !entry.out) this.#send(entry);
  }

  closed(code) {
    for (const entry of this.#lines.values()) {
      if (!entry.out) continue; // never went out: it goes on the next channel
      entry.out = false;
      if (code !== SERVICE_RESTART) entry.state = "unsent";
      this.#panel.outgoing = { ...entry };
    }
  }

  #send(entry) {
    entry.state = "sending";
    entry.out = this.#chat.sendJson({ type: "say", body: entry.body, line: entry.line });
    this.#panel.outgoing = { ...entry };
  }
}

/** Opens the chat channel at `${robotPath}/chat` and connects it to panel; returns the Channel. */
export function connectChat(robotPath, panel) {
  const chat = new Channel(`${robotPath}/chat`);
  const outbox = new ChatOutbox(chat, panel);
  chat.addEventListener("statechange", ({ detail }) => {
    panel.link = detail.phase;
    if (detail.phase === "reconnecting" || detail.phase === "closed") outbox.closed(detail.code);
  });
  chat.addEventListener("open", () => outbox.opened());
  chat.addEventListener("message", ({ detail }) => {
    const message = parseJsonMessage(detail);
    if (message?.type === "history") panel.history = message;
    else if (message?.type === "message") panel.message = message.message;
    else if (message?.type === "deleted") panel.deleted = message.id;
    else if (message?.type === "sent") outbox.answered(message.line, message.id);
    else if (message?.type === "error") {
      outbox.answered(message.line, null);
      panel.error = message;
    }
  });
  panel.addEventListener("chat-send", ({ detail }) => outbox.write(detail.body));
  panel.addEventListener("chat-resend", ({ detail }) => outbox.sendAgain(detail.line));
  panel.addEventListener("chat-delete", ({ detail }) => chat.sendJson({ type: "delete", id: detail.id }));
  window.addEventListener("online", () => chat.retryNow());
  return chat;
}

registerFeedService("chat", (wiring, descriptor, panel) => { connectChat(wiring.robotPath, panel); });
