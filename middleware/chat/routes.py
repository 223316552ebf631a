"""Chat over HTTP (for tests, reconnects and scripts) and the chat WebSocket's registration."""

from __future__ import annotations

from datetime import UTC, datetime

from flask import Blueprint, jsonify, request
from flask_login import current_user, login_required

from middleware.auth.schemas import InvalidField
from middleware.chat import services, sockets
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.robots.registry import robot_registry

blueprint = Blueprint("chat", __name__)
sockets.register(blueprint)


def _require_robot(robot_name: str) -> None:
    if robot_registry().get(robot_name) is None:
        raise ApiError(404, "unknown_robot", f"There is no robot named {robot_name!r}.", "robot_name")


@blueprint.get("/api/robots/<robot_name>/chat")
@login_required
def list_messages(robot_name: str):  # type: ignore[no-untyped-def]
    """The last 50 visible messages, or those after ?after_id=N (at most 50)."""
    _require_robot(robot_name)
    raw = request.args.get("after_id", "0")
    if not raw.isdigit() or len(raw) > 16:
        raise ApiError(400, "invalid_field", "after_id must be a whole number (0 for the latest messages).", "after_id")
    views = services.recent_messages(get_session(), robot_name, after_id=int(raw))
    return jsonify({"robot_name": robot_name, "can_moderate": services.may_moderate(current_user),
                    "messages": [v.to_dict() for v in views]})


@blueprint.post("/api/robots/<robot_name>/chat")
@login_required
def post_message(robot_name: str):  # type: ignore[no-untyped-def]
    """Posts {"body": "..."} to the robot's chat."""
    _require_robot(robot_name)
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", "Send the message as a JSON object with a body.", "body")
    session = get_session()
    try:
        view = services.post_message(session, robot_name, current_user, data.get("body"), datetime.now(UTC))
    except InvalidField as invalid:
        session.rollback()
        raise ApiError(400, "invalid_field", invalid.message, invalid.field) from None
    except services.ChatRefused as refused:
        session.rollback()
        raise ApiError(refused.status, refused.code, refused.message, refused.field) from None
    session.commit()
    return jsonify({"message": view.to_dict()}), 201


@blueprint.delete("/api/robots/<robot_name>/chat/<int:message_id>")
@login_required
def delete_message(robot_name: str, message_id: int):  # type: ignore[no-untyped-def]
    """Soft-deletes a message (tutors and admins)."""
    _require_robot(robot_name)
    session = get_session()
    try:
        services.delete_message(session, robot_name, current_user, message_id, datetime.now(UTC))
    except services.ChatRefused as refused:
        session.rollback()
        raise ApiError(refused.status, refused.code, refused.message, refused.field) from None
    session.commit()
    return jsonify({"deleted": message_id})
