"""The chat channel /ws/robots/<name>/chat: history on connect, then new and deleted messages as they happen."""

from __future__ import annotations

import asyncio
import functools
from datetime import UTC, datetime

from flask import current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user

from middleware.access.sockets import open_robot_channel
from middleware.chat import services
from middleware.chat.hub import chat_hub
from middleware.chat.schemas import parse_chat_command
from middleware.db import session_factory, unit_of_work
from middleware.errors import Refused
from middleware.live.loop import Continuation, blocking_work
from middleware.live.wire import LiveSocket
from middleware.models import User
from middleware.realtime import Channels, WebSocket, as_json, send_json

IDLE_WAKE_S = 5.0  # the hub nudges a socket when its room has news; this only bounds a lost nudge


def _error(code: str, message: str, field: str | None, line: str | None = None) -> dict[str, object]:
    return {"type": "error", "code": code, "message": message, "field": field, "line": line}


def _handle(robot_name: str, user_id: int, raw: object) -> dict[str, object] | None:
    """Carries out a chat command; the answer for its sender, if any (a say's names its line's key, so the browser
    knows which line was stored or refused, and that every line without an answer was never read)."""
    line = None
    try:
        command = parse_chat_command(raw)
        line = command.line
        with unit_of_work(current_app) as session:  # one message, one transaction
            user = session.get(User, user_id)
            if user is None or not user.is_active:
                return _error("not_logged_in", gettext("Your account is no longer active."), None)
            if command.kind == "say":
                sent = services.post_message(session, robot_name, user, command.body, datetime.now(UTC)).id
            else:
                services.delete_message(session, robot_name, user, command.message_id, datetime.now(UTC))
                sent = None
    except Refused as refused:
        return _error(refused.code, refused.message, refused.field, line)
    return None if sent is None else {"type": "sent", "id": sent, "line": line}


def chat_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """Sends the last 50 messages, then new ones and deletions; takes say and delete commands."""
    if open_robot_channel(ws, robot_name) is None:
        return None
    return room_channel(ws, robot_name)


def room_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """A chat room's channel for a user its caller let in: a robot's room (above), or another area's (a class's,
    named so that no robot is: "class:<id>")."""
    user_id = int(current_user.get_id())
    can_moderate = current_user.role in services.MODERATOR_ROLES
    subscription = chat_hub(current_app._get_current_object()).subscribe(robot_name)  # type: ignore[attr-defined]
    try:
        with session_factory(current_app)() as session:
            history = services.recent_messages(session, robot_name)
        subscription.after_id = history[-1].id if history else 0
        send_json(ws, {"type": "history", "robot_name": robot_name, "can_moderate": can_moderate,
                       "user": current_user.username, "messages": [m.to_dict(user_id, can_moderate) for m in history]})
    except BaseException:
        subscription.close()
        raise
    work = blocking_work()

    async def converse(live: LiveSocket) -> None:
        loop = asyncio.get_running_loop()
        subscription.on_put = functools.partial(loop.call_soon_threadsafe, live.nudge)
        try:
            while live.connected:
                for kind, payload in subscription.drain():
                    if kind == "message":
                        view: services.MessageView = payload  # type: ignore[assignment]
                        await live.send(as_json({"type": "message", "message": view.to_dict(user_id, can_moderate)}))
                    else:
                        await live.send(as_json({"type": "deleted", "id": payload}))
                raw = await live.receive(timeout=IDLE_WAKE_S)
                if raw is not None:
                    answer = await work(_handle, robot_name, user_id, raw)
                    if answer is not None:
                        await live.send(as_json(answer))
        finally:
            subscription.close()

    return converse


def register(sock: Channels) -> None:
    """Declares the chat channel."""
    sock.route("/ws/robots/<robot_name>/chat", endpoint="chat_channel")(chat_channel)
