"""Chat over HTTP (for tests, reconnects and scripts) and the chat WebSocket's registration."""

from __future__ import annotations

from datetime import UTC, datetime

from flask import Blueprint, jsonify, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.access.commands import robot_commands
from middleware.api.contract import ID, OBJECT, STRING, about, array, described, obj, whole
from middleware.chat import services
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.validation import decimal_int

blueprint = Blueprint("chat", __name__)


def _require_robot(robot_name: str) -> None:
    robot_commands().require(robot_name, int(current_user.get_id()))


@blueprint.get("/api/robots/<robot_name>/chat")
@login_required
@described(
    query={"after_id": whole(0, 2**63 - 1)},
    answers={200: obj(("robot_name",), robot_name=STRING, messages=array(OBJECT))},
)
def list_messages(robot_name: str) -> ResponseReturnValue:
    """The last 50 visible messages, or those after ?after_id=N (at most 50)."""
    _require_robot(robot_name)
    after_id = decimal_int(request.args.get("after_id", "0"), 0)
    if after_id is None:
        raise ApiError(400, "invalid_field", gettext("after_id must be a whole number (0 for the latest messages)."),
                                             "after_id")
    views = services.recent_messages(get_session(), robot_name, after_id=after_id)
    moderator = services.may_moderate(current_user)
    return jsonify({"robot_name": robot_name, "can_moderate": moderator,
                    "messages": [v.to_dict(current_user.id, moderator) for v in views]})


@blueprint.post("/api/robots/<robot_name>/chat")
@login_required
@described(
    body=obj(("body",), body=about("the message's text")),
    answers={201: obj(("message",), message=OBJECT)},
    refusals=(429,),
)
def post_message(robot_name: str) -> ResponseReturnValue:
    """Posts {"body": "..."} to the robot's chat."""
    _require_robot(robot_name)
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", gettext("Send the message as a JSON object with a body."), "body")
    view = services.post_message(get_session(), robot_name, current_user, data.get("body"), datetime.now(UTC))
    return jsonify({"message": view.to_dict(current_user.id, True)}), 201


@blueprint.delete("/api/robots/<robot_name>/chat/<int:message_id>")
@login_required
@described(answers={200: obj(("deleted",), deleted=ID)})
def delete_message(robot_name: str, message_id: int) -> ResponseReturnValue:
    """Soft-deletes a message (tutors and admins)."""
    _require_robot(robot_name)
    services.delete_message(get_session(), robot_name, current_user, message_id, datetime.now(UTC))
    return jsonify({"deleted": message_id})
