"""The chat channel /ws/robots/<name>/chat: history on connect, then new and deleted messages as they happen."""

from __future__ import annotations

import json
from datetime import UTC, datetime

from flask import Blueprint, current_app
from flask_login import current_user

from middleware.auth.schemas import InvalidField
from middleware.chat import services
from middleware.chat.hub import chat_hub
from middleware.chat.schemas import parse_chat_command
from middleware.db import session_factory
from middleware.lab.sockets import open_robot_channel, sock
from middleware.models import User

RECEIVE_WAIT_S = 0.2  # how long a socket waits for input before passing on queued events


def _send(ws, message: dict[str, object]) -> None:  # type: ignore[no-untyped-def]
    ws.send(json.dumps(message, separators=(",", ":")))


def _error(ws, code: str, message: str, field: str | None) -> None:  # type: ignore[no-untyped-def]
    _send(ws, {"type": "error", "code": code, "message": message, "field": field})


def _handle(ws, robot_name: str, user_id: int, raw: object) -> None:  # type: ignore[no-untyped-def]
    try:
        command = parse_chat_command(raw)
    except InvalidField as invalid:
        _error(ws, "invalid_field", invalid.message, invalid.field)
        return
    with session_factory(current_app)() as session:
        user = session.get(User, user_id)
        if user is None or not user.is_active:
            _error(ws, "not_logged_in", "Your account is no longer active.", None)
            return
        try:
            if command.kind == "say":
                view = services.post_message(session, robot_name, user, command.body, datetime.now(UTC))
                session.commit()
                _send(ws, {"type": "sent", "id": view.id})
            else:
                services.delete_message(session, robot_name, user, command.message_id, datetime.now(UTC))
                session.commit()
        except services.ChatRefused as refused:
            session.rollback()
            _error(ws, refused.code, refused.message, refused.field)


def chat_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
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
                   "user": current_user.username, "messages": [m.to_dict() for m in history]})
        while ws.connected:
            raw = ws.receive(timeout=RECEIVE_WAIT_S)
            if raw is not None:
                _handle(ws, robot_name, user_id, raw)
            for kind, payload in subscription.drain():
                if kind == "message":
                    _send(ws, {"type": "message", "message": payload})
                else:
                    _send(ws, {"type": "deleted", "id": payload})
    finally:
        subscription.close()


def register(blueprint: Blueprint) -> None:
    """Adds the channel to blueprint (so every app that registers the blueprint gets it)."""
    sock.route("/ws/robots/<robot_name>/chat", bp=blueprint)(chat_channel)
