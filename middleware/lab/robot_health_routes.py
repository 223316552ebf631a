"""A robot's health page and its API: what a tutor or an admin diagnoses a robot by, and the recoveries they take
(restart its process, carry it to its dock, clear its map), each written into the robot's maintenance log."""

from __future__ import annotations

import time

from flask import Blueprint, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.access.commands import robot_commands
from middleware.api.contract import BOOLEAN, OBJECT, STRING, array, described, obj, one_of
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lab import maintenance
from middleware.models import User
from middleware.robots.link import RobotUnavailable
from middleware.robots.registry import robot_registry

blueprint = Blueprint("robot_health", __name__)


def _actor() -> User:
    return get_session().get(User, int(current_user.get_id()))  # type: ignore[return-value]


def _maintainer(robot_name: str) -> None:
    """404 for a robot nobody knows, 403 for someone who may not maintain it."""
    registry = robot_registry()
    if registry.get(robot_name) is None:
        raise ApiError(404, "unknown_robot", gettext("There is no robot named %(value)s.", value=repr(robot_name[:64])),
                       "robot_name")
    maintenance.require_maintainer(get_session(), _actor(), registry.owner_of(robot_name))


def _health_dict(robot_name: str) -> dict[str, object]:
    link = robot_registry().get(robot_name)
    try:
        health = link.health() if link is not None else None
    except RobotUnavailable as offline:
        return {"online": False, "message": offline.message}
    if health is None:
        return {"online": False, "message": f"{robot_name} is not registered any more."}
    return {
        "online": True,
        "real_time_factor": round(health.real_time_factor, 3), "loop_lag_ms_p50": round(health.loop_lag_ms_p50, 1),
        "loop_lag_ms_max": round(health.loop_lag_ms_max, 1), "parked": health.parked,
        "cpu_percent": round(health.cpu_percent, 1), "memory_mb": round(health.rss_bytes / 2**20, 1),
        "uptime_s": round(health.uptime_s, 1), "version": health.version, "pid": health.pid,
        "restartable": health.restartable, "restarts": health.restarts,
        "faults": [{"at_unix_s": f.unix_s, "kind": f.kind, "message": f.message} for f in health.faults],
        "log_tail": list(health.log_tail),
    }


@blueprint.get("/robots/<robot_name>/health")
@login_required
def page(robot_name: str) -> ResponseReturnValue:
    """The robot's health, for the tutors of its courses and admins."""
    _maintainer(robot_name)
    return render_template("lab/robot_health.html", robot_name=robot_name)


@blueprint.get("/api/robots/<robot_name>/health")
@login_required
@described(answers={200: obj(("robot_name", "health", "maintenance"), robot_name=STRING, health=OBJECT,
                             maintenance=array(OBJECT), server_time_unix_s={"type": "number"})})
def health(robot_name: str) -> ResponseReturnValue:
    """The robot's loop, process, faults and log tail now (online: false when it does not answer), and its
    maintenance log."""
    _maintainer(robot_name)
    return jsonify({
        "robot_name": robot_name, "health": _health_dict(robot_name), "server_time_unix_s": time.time(),
        "maintenance": [{"at": entry.created_at.isoformat(), "actor": username, "action": entry.action,
                         "outcome": entry.outcome}
                        for entry, username in maintenance.recent(get_session(), robot_name)],
    })


@blueprint.post("/api/robots/<robot_name>/maintenance")
@login_required
@described(body=obj(("action",), action=one_of(*maintenance.ACTIONS)),
           answers={200: obj(("action", "message"), action=STRING, message=STRING, restarting=BOOLEAN)},
           refusals=(409, 503))
def act(robot_name: str) -> ResponseReturnValue:
    """{"action": "restart" | "dock" | "clear_map"}: taken under the robot's current token, whoever holds it, and
    written into its maintenance log."""
    _maintainer(robot_name)
    action = (request.get_json(silent=True) or {})["action"]
    robot = robot_commands().for_maintenance(robot_name)
    if action == "restart":
        answer = robot.restart()
        message = answer.message
    elif action == "dock":
        robot.return_to_dock()
        message = f"{robot_name} is back at its dock; its odometry restarts there."
    else:
        robot.clear_map()
        message = f"{robot_name}'s map was cleared."
    maintenance.record(get_session(), _actor(), robot_name, action, message)
    return jsonify({"action": action, "message": message, "restarting": action == "restart"})
