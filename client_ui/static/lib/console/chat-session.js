// Wires a <chat-panel> to the robot's chat socket: history on every (re)connect, then new messages,
// deletions and errors; the panel's chat-send / chat-delete events become socket commands.
// It registers the console's "chat" feed service (feed-services.js).

import { Channel, parseJsonMessage } from "../transport.js";
import { registerFeedService } from "./feed-services.js";

/** Opens the chat channel at `${robotPath}/chat` and connects it to panel; returns the Channel. */
export function connectChat(robotPath, panel) {
  const chat = new Channel(`${robotPath}/chat`);
  chat.addEventListener("statechange", ({ detail }) => { panel.link = detail.phase; });
  chat.addEventListener("message", ({ detail }) => {
    const message = parseJsonMessage(detail);
    if (message?.type === "history") panel.history = message;
    else if (message?.type === "message") panel.message = message.message;
    else if (message?.type === "deleted") panel.deleted = message.id;
    else if (message?.type === "error") panel.error = message;
  });
  panel.addEventListener("chat-send", ({ detail }) => {
    if (!chat.sendJson({ type: "say", body: detail.body })) panel.error = { message: "Not connected; try again in a moment." };
  });
  panel.addEventListener("chat-delete", ({ detail }) => chat.sendJson({ type: "delete", id: detail.id }));
  window.addEventListener("online", () => chat.retryNow());
  return chat;
}

registerFeedService("chat", (wiring, descriptor, panel) => { connectChat(wiring.robotPath, panel); });
