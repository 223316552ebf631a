"""Practice robot pages and API: start, stop, status, commands, goals, and the camera channel."""

from __future__ import annotations

import re
import time

from flask import Blueprint, jsonify, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.api.contract import BOOLEAN, OBJECT, STRING, described, nullable, number, obj, whole
from middleware.db import after_commit, get_session
from middleware.errors import ApiError
from middleware.lab.sockets import camera_relay
from middleware.live.loop import Continuation
from middleware.realtime import CLOSE_NOT_FOUND, Channels, WebSocket, refuse
from middleware.teaching.command_form import parse_command
from middleware.teaching.practice_robots import practice_manager, practice_name
from middleware.teaching.targets import (
    COMMAND_ANSWER,
    PRACTICE_TARGET,
    execute,
    goal_state,
    resolve_target,
    skill_schemas,
)

blueprint = Blueprint("practice", __name__)
GOAL_ID = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


def _user_id() -> int:
    return int(current_user.get_id())


# The user's practice robot, as status_dict and _answer say it (stopped: only DELETE's answer).
PRACTICE = obj(("running", "starting", "name", "console_url", "in_use", "cap", "idle_stop_s"),
               running=BOOLEAN, starting=BOOLEAN, name=nullable(STRING), console_url=nullable(STRING),
               in_use=whole(0), cap=whole(0), idle_stop_s=number(), stopped=BOOLEAN)


def status_dict(user_id: int) -> dict[str, object]:
    """The user's practice robot (or none, or starting) and how many slots are taken."""
    robot = practice_manager().get(user_id)
    if robot is not None:
        return _answer(robot.name, running=True)
    return _answer(None, running=False, starting=practice_manager().starting(user_id))


def _answer(name: str | None, running: bool, starting: bool = False, **more: object) -> dict[str, object]:
    # Reads no row of the user's robot: a request that changed it reads what it wrote, not the committed table.
    manager = practice_manager()
    return {"running": running, "starting": starting, "name": name,
            "console_url": url_for("lab.console", robot_name=name) if running and name else None,
            "in_use": manager.count(), "cap": manager.limit(), "idle_stop_s": manager.idle_s, **more}


@blueprint.get("/practice")
@login_required
def page() -> ResponseReturnValue:
    """The practice robot page, with the link to its full console."""
    name = practice_name(current_user.username, _user_id())
    return render_template("teaching/practice.html", console_url=url_for("lab.console", robot_name=name))


@blueprint.get("/api/practice")
@login_required
@described(answers={200: PRACTICE})
def status() -> ResponseReturnValue:
    """Whether the user's practice robot runs."""
    return jsonify(status_dict(_user_id()))


@blueprint.post("/api/practice")
@login_required
@described(answers={200: PRACTICE, 202: PRACTICE}, refusals=(409, 429, 503))
def start() -> ResponseReturnValue:
    """Claims the user's practice robot, which the farm starts once the claim is committed (202: the page follows
    it to running), or answers the running one (200)."""
    manager = practice_manager()
    pending = manager.begin_start(get_session(), _user_id(), current_user.username)
    if pending is None:
        return jsonify(status_dict(_user_id())), 200
    after_commit(pending.run_quietly)
    return jsonify(_answer(pending.name, running=False, starting=True)), 202


@blueprint.delete("/api/practice")
@login_required
@described(answers={200: PRACTICE})
def stop() -> ResponseReturnValue:
    """Stops the user's practice robot."""
    manager = practice_manager()
    name = manager.begin_stop(get_session(), _user_id())
    if name is not None:
        after_commit(lambda: manager.finish_stop(name))
    return jsonify(_answer(None, running=False, stopped=name is not None))


@blueprint.post("/api/practice/commands")
@login_required
@described(
    body=obj(("command",), command=obj(description="a declarative command: {kind, ...}")),
    answers={202: COMMAND_ANSWER},
    refusals=(409, 503),
)
def command() -> ResponseReturnValue:
    """Runs one declarative command on the practice robot: {"command": {...}}."""
    received_at = time.perf_counter()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext('Send a JSON object: {"command": {...}}.'), "body")
    target = resolve_target(PRACTICE_TARGET, _user_id())
    schemas = skill_schemas(target.link)
    return jsonify(execute(target, parse_command(body.get("command"), schemas), received_at)), 202


@blueprint.get("/api/robots/<target_name>/command-goals/<goal_id>")
@login_required
@described(answers={200: obj(("goal",), goal=OBJECT)}, refusals=(409, 503))
def goal(target_name: str, goal_id: str) -> ResponseReturnValue:
    """A goal of the practice robot ("practice") or of a lab robot the user controls."""
    if not GOAL_ID.fullmatch(goal_id):
        raise ApiError(404, "unknown_goal", gettext("There is no goal with that id."), "goal_id")
    return jsonify({"goal": goal_state(resolve_target(target_name, _user_id()), goal_id)})


def camera_channel(ws: WebSocket) -> Continuation | None:
    """The camera of the user's own practice robot (none during their obstacle-zone test, as every camera)."""
    robot = practice_manager().get(_user_id())
    if robot is None:
        refuse(ws, CLOSE_NOT_FOUND, "no_practice_robot", gettext("Start your practice robot first."))
        return None
    return camera_relay(ws, robot.link.camera)


def register(sock: Channels) -> None:
    """Declares the practice camera channel."""
    sock.route("/ws/practice/camera", endpoint="practice_camera_channel")(camera_channel)
