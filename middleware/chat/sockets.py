"""The chat channel /ws/robots/<name>/chat: history on connect, then new and deleted messages as they happen."""

from __future__ import annotations

import json
from datetime import UTC, datetime

from flask import current_app
from flask_login import current_user

from middleware.access.sockets import open_robot_channel
from middleware.chat import services
from middleware.chat.hub import chat_hub
from middleware.chat.schemas import parse_chat_command
from middleware.db import session_factory, unit_of_work
from middleware.errors import Refused
from middleware.models import User
from middleware.realtime import Channels, WebSocket

RECEIVE_WAIT_S = 0.2  # how long a socket waits for input before passing on queued events


def _send(ws: WebSocket, message: dict[str, object]) -> None:
    ws.send(json.dumps(message, separators=(",", ":")))


def _error(ws: WebSocket, code: str, message: str, field: str | None) -> None:
    _send(ws, {"type": "error", "code": code, "message": message, "field": field})


def _handle(ws: WebSocket, robot_name: str, user_id: int, raw: object) -> None:
    try:
        command = parse_chat_command(raw)
        with unit_of_work(current_app) as session:  # one message, one transaction
            user = session.get(User, user_id)
            if user is None or not user.is_active:
                _error(ws, "not_logged_in", "Your account is no longer active.", None)
                return
            if command.kind == "say":
                sent = services.post_message(session, robot_name, user, command.body, datetime.now(UTC)).id
            else:
                services.delete_message(session, robot_name, user, command.message_id, datetime.now(UTC))
                sent = None
    except Refused as refused:
        _error(ws, refused.code, refused.message, refused.field)
        return
    if sent is not None:
        _send(ws, {"type": "sent", "id": sent})


def chat_channel(ws: WebSocket, robot_name: str) -> None:
    """Sends the last 50 messages, then new ones and deletions; takes say and delete commands."""
    if open_robot_channel(ws, robot_name) is None:
        return
    user_id = int(current_user.get_id())
    can_moderate = current_user.role in services.MODERATOR_ROLES
    subscription = chat_hub(current_app._get_current_object()).subscribe(robot_name)  # type: ignore[attr-defined]
    try:
        with session_factory(current_app)() as session:
            history = services.recent_messages(session, robot_name)
        subscription.after_id = history[-1].id if history else 0
        _send(ws, {"type": "history", "robot_name": robot_name, "can_moderate": can_moderate,
                   "user": current_user.username,
                   "messages": [m.to_dict(user_id, can_moderate) for m in history]})
        while ws.connected:
            raw = ws.receive(timeout=RECEIVE_WAIT_S)
            if raw is not None:
                _handle(ws, robot_name, user_id, raw)
            for kind, payload in subscription.drain():
                if kind == "message":
                    view: services.MessageView = payload  # type: ignore[assignment]
                    _send(ws, {"type": "message", "message": view.to_dict(user_id, can_moderate)})
                else:
                    _send(ws, {"type": "deleted", "id": payload})
    finally:
        subscription.close()


def register(sock: Channels) -> None:
    """Declares the chat channel."""
    sock.route("/ws/robots/<robot_name>/chat", endpoint="chat_channel")(chat_channel)
