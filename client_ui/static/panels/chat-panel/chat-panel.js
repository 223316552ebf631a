// <chat-panel>: the robot's chat room. In: `history` ({messages, can_moderate}), `message` (one message),
// `deleted` (an id), `error` ({message, field}), `link` ("open" | "connecting" | "closed"), and the person's own
// lines not yet stored: `outgoing` ({line, body, state: "sending" | "unsent"}), `acknowledged` ({line, id}: the row
// stays until message id arrives), `withdrawn` ({line, body}: refused; the text goes back to an empty input).
// Out: "chat-send" (detail {body}), "chat-resend" (detail {line}), "chat-delete" (detail {id}) and
// "panel-attention" on a new message (the console counts it on the Chat tab while another is shown).
// Text reaches the DOM only as text.

import { h } from "../../lib/dom.js";
import { PanelElement } from "../panel-base.js";
import { registerPanel } from "../registry.js";
import { DATE_LOCALE, t } from "../../lib/i18n.js";

const MAX_CHARS = 500;

/** Local HH:MM of an ISO time; "" when it cannot be read. */
export function formatTime(iso) {
  const date = new Date(iso);
  if (Number.isNaN(date.getTime())) return "";
  return date.toLocaleTimeString(DATE_LOCALE, { hour: "2-digit", minute: "2-digit" });
}

export class ChatPanel extends PanelElement {
  #list;
  #input;
  #send;
  #errorLine;
  #empty;
  #items = new Map();
  #pending = new Map(); // line key -> row of a line not yet in the room
  #awaited = new Map(); // stored id -> line key, until the message itself arrives
  #canModerate = false;

  build() {
    this.classList.add("panel", "chat");
    const titleId = "chat-title";
    this.#list = h("ol", { class: "chat__list", role: "log", "aria-live": "polite", "aria-labelledby": titleId,
      "data-field": "chat-messages" });
    this.#empty = h("p", { class: "chat__empty muted", text: t("No messages yet. Say hello.") });
    this.#input = h("input", { id: "chat-input", name: "body", type: "text", maxlength: String(MAX_CHARS),
      autocomplete: "off", enterkeyhint: "send", "aria-describedby": "chat-error", disabled: true });
    this.#send = h("button", { type: "submit", class: "button button--primary chat__send", text: t("Send"), disabled: true });
    this.#errorLine = h("p", { class: "chat__error", id: "chat-error", role: "alert", hidden: true });
    const form = h("form", { class: "chat__form", onsubmit: (event) => this.#submit(event) },
      h("label", { for: "chat-input", class: "visually-hidden", text: t("Message to everyone on this robot") }),
      this.#input, this.#send);
    this.append(h("h2", { class: "panel__title", id: titleId, text: t("Chat") }), this.#list, this.#empty, form,
      this.#errorLine);
  }

  #submit(event) {
    event.preventDefault();
    const body = this.#input.value.trim();
    if (!body) {
      this.error = { message: t("Write something before sending.") };
      return;
    }
    this.emit("chat-send", { body });
    this.#input.value = "";
    this.#errorLine.hidden = true;
  }

  #row(message) {
    const time = h("time", { class: "chat__time", datetime: message.created_at, text: formatTime(message.created_at) });
    const staff = message.author_role === "tutor" || message.author_role === "admin";
    const item = h("li", { class: "chat__item", "data-message-id": String(message.id) },
      h("div", { class: "chat__meta" },
        h("span", { class: "chat__author", text: message.author }),
        staff && h("span", { class: `chat__role chat__role--${message.author_role}`, text: message.author_role }),
        time,
        this.#canModerate && h("button", {
          type: "button", class: "chat__delete", text: t("Delete"),
          "aria-label": t("Delete the message from {author}", { author: message.author }),
          onclick: () => this.emit("chat-delete", { id: message.id }),
        })),
      h("p", { class: "chat__body", "data-field": "chat-body", text: message.body }));
    return item;
  }

  #pendingRow(line, body, state) {
    const unsent = state === "unsent";
    return h("li", { class: `chat__item chat__item--pending${unsent ? " chat__item--unsent" : ""}`, "data-line": line },
      h("div", { class: "chat__meta" },
        h("span", { class: "chat__author", text: t("You") }),
        h("span", { class: "chat__status", "data-field": "chat-status",
          text: unsent ? t("Not sent: the connection was lost") : t("Sending…") }),
        unsent && h("button", { type: "button", class: "chat__resend", text: t("Send again"),
          onclick: () => this.emit("chat-resend", { line }) })),
      h("p", { class: "chat__body", "data-field": "chat-pending-body", text: body }));
  }

  #forget(line) {
    this.#pending.get(line)?.remove();
    this.#pending.delete(line);
    this.#empty.hidden = this.#items.size > 0 || this.#pending.size > 0;
  }

  #append(message) {
    if (this.#items.has(message.id)) return;
    const nearBottom = this.#list.scrollHeight - this.#list.scrollTop - this.#list.clientHeight < 40;
    const row = this.#row(message);
    this.#items.set(message.id, row);
    const awaited = this.#awaited.get(message.id);
    if (awaited !== undefined) {
      this.#awaited.delete(message.id);
      this.#forget(awaited);
    }
    this.#list.insertBefore(row, this.#pending.values().next().value ?? null); // lines still sending stay last
    this.#empty.hidden = true;
    if (nearBottom) this.#list.scrollTop = this.#list.scrollHeight;
  }

  set history(value) {
    this.ensureBuilt();
    this.#canModerate = Boolean(value?.can_moderate);
    this.#items.clear();
    this.#list.replaceChildren();
    const pending = [...this.#pending.values()];
    this.#list.replaceChildren(...pending);
    for (const message of value?.messages ?? []) this.#append(message);
    this.#empty.hidden = this.#items.size > 0 || this.#pending.size > 0;
    this.#list.scrollTop = this.#list.scrollHeight;
  }

  set outgoing(value) {
    this.ensureBuilt();
    if (!value?.line) return;
    const row = this.#pendingRow(value.line, value.body, value.state);
    const old = this.#pending.get(value.line);
    if (old) old.replaceWith(row);
    else this.#list.append(row);
    this.#pending.set(value.line, row);
    this.#empty.hidden = true;
    this.#list.scrollTop = this.#list.scrollHeight;
  }

  set acknowledged(value) {
    this.ensureBuilt();
    if (this.#items.has(value?.id)) this.#forget(value.line);
    else if (this.#pending.has(value?.line)) this.#awaited.set(value.id, value.line);
  }

  set withdrawn(value) {
    this.ensureBuilt();
    this.#forget(value?.line);
    if (!this.#input.value && typeof value?.body === "string") this.#input.value = value.body;
  }

  set message(value) {
    this.ensureBuilt();
    if (value && typeof value.id === "number") {
      this.#append(value);
      this.emit("panel-attention", { reason: "message" });
    }
  }

  set deleted(id) {
    this.ensureBuilt();
    this.#items.get(id)?.remove();
    this.#items.delete(id);
    const awaited = this.#awaited.get(id);
    if (awaited !== undefined) {
      this.#awaited.delete(id);
      this.#forget(awaited);
    }
    this.#empty.hidden = this.#items.size > 0 || this.#pending.size > 0;
  }

  set error(value) {
    this.ensureBuilt();
    this.#errorLine.textContent = value?.message ?? "";
    this.#errorLine.hidden = !value?.message;
  }

  set link(phase) {
    this.ensureBuilt();
    const open = phase === "open";
    this.#input.disabled = !open;
    this.#send.disabled = !open;
    this.#input.placeholder = open ? t("Message") : phase === "closed" ? t("Chat closed") : t("Connecting…");
  }
}

export const register = registerPanel({
  kind: "chat", tag: "chat-panel", element: ChatPanel, stylesheets: [new URL("./chat-panel.css", import.meta.url)],
  feeds: [{ service: "chat" }],
});
