"""The low-level commands API: a robot's velocity ceilings and watchdog timeout (GET to watch, POST to change)."""

from __future__ import annotations

from flask import Blueprint, jsonify, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.access.commands import robot_commands
from middleware.access.limits import UNITS, changeable_fields, check_permitted, parse_limits_request
from middleware.api.contract import OBJECT, STRING, array, described, number, obj
from middleware.db import get_session
from middleware.errors import written_number
from middleware.robots.messages import limits_dict

blueprint = Blueprint("limits", __name__)


def _user_id() -> int:
    return int(current_user.get_id())


@blueprint.get("/api/robots/<robot_name>/limits")
@login_required
@described(answers={200: obj(("limits", "may_change"), limits=OBJECT, may_change=array(STRING))}, refusals=(503,))
def limits(robot_name: str) -> ResponseReturnValue:
    """The limits in force, their ranges, and which of them this user may change (anyone who may watch the robot)."""
    robot = robot_commands().for_user(robot_name, _user_id())
    answer = robot.limits()
    return jsonify({"limits": limits_dict(answer), "may_change": list(changeable_fields(get_session(), current_user))})


@blueprint.post("/api/robots/<robot_name>/limits")
@login_required
@described(
    body=obj(max_linear_mps=number(0), max_angular_radps=number(0), watchdog_s=number(0)),
    answers={200: obj(("limits", "may_change"), limits=OBJECT, may_change=array(STRING), message=STRING)},
    refusals=(409, 503),
)
def set_limits(robot_name: str) -> ResponseReturnValue:
    """{max_linear_mps?, max_angular_radps?, watchdog_s?} (0 or absent keeps a value): the controller changes the
    settings their role and course allow; they bind the drive pad, skills and plans alike."""
    robot = robot_commands().for_user(robot_name, _user_id())
    values = parse_limits_request(request.get_json(silent=True))
    permitted = changeable_fields(get_session(), current_user)
    check_permitted(values, permitted)
    answer = robot.set_limits(values.get("max_linear_mps", 0.0), values.get("max_angular_radps", 0.0),
                              values.get("watchdog_s", 0.0))
    saved = ", ".join(f"{name} {written_number(value, 'g')} {UNITS[name]}" for name, value in values.items())
    return jsonify({"limits": limits_dict(answer), "may_change": list(permitted),
                    "message": gettext("Saved: %(settings)s.", settings=saved)})
