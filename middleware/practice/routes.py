"""Practice robot pages and API: start, stop, status, commands, goals, and the camera channel."""

from __future__ import annotations

import re
import time

from flask import Blueprint, jsonify, render_template, request, url_for
from flask_login import current_user, login_required

from middleware.errors import ApiError
from middleware.lab.sockets import CLOSE_NOT_LOGGED_IN, _refuse, relay_stream, sock
from middleware.lessons.commands import CommandInvalid, parse_command
from middleware.practice.control import PRACTICE_TARGET, execute, goal_state, resolve_target, skill_schemas
from middleware.practice.manager import PracticeCapReached, PracticeStartFailed, practice_manager, practice_name
from middleware.robots.link import RobotUnavailable

blueprint = Blueprint("practice", __name__)
GOAL_ID = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


def _user_id() -> int:
    return int(current_user.get_id())


def status_dict(user_id: int) -> dict[str, object]:
    """The user's practice robot (or none) and how many slots are taken."""
    manager = practice_manager()
    robot = manager.get(user_id)
    return {"running": robot is not None, "name": robot.name if robot else None,
            "console_url": url_for("lab.console", robot_name=robot.name) if robot else None,
            "in_use": manager.count(), "cap": manager.cap, "idle_stop_s": manager.idle_s}


def _hand_back_control(robot_name: str, user_id: int) -> None:
    """A restarted practice robot obeys the owner's queue token at once if they hold its control already."""
    from middleware.access.coordinator import access_coordinator

    coordinator = access_coordinator()
    state = coordinator.snapshot(robot_name)
    if state.controller_id == user_id and state.token:
        coordinator.sync_token(state, force=True)


@blueprint.get("/practice")
@login_required
def page():  # type: ignore[no-untyped-def]
    """The practice robot page, with the link to its full console."""
    name = practice_name(current_user.username, _user_id())
    return render_template("teaching/practice.html", console_url=url_for("lab.console", robot_name=name))


@blueprint.get("/api/practice")
@login_required
def status():  # type: ignore[no-untyped-def]
    """Whether the user's practice robot runs."""
    return jsonify(status_dict(_user_id()))


@blueprint.post("/api/practice")
@login_required
def start():  # type: ignore[no-untyped-def]
    """Starts the user's practice robot (or answers the running one)."""
    try:
        robot = practice_manager().start(_user_id(), current_user.username)
    except PracticeCapReached as full:
        raise ApiError(429, "practice_cap_reached", str(full)) from None
    except PracticeStartFailed as failed:
        raise ApiError(503, "practice_start_failed", str(failed)) from None
    _hand_back_control(robot.name, _user_id())
    return jsonify(status_dict(_user_id())), 201


@blueprint.delete("/api/practice")
@login_required
def stop():  # type: ignore[no-untyped-def]
    """Stops the user's practice robot."""
    stopped = practice_manager().stop(_user_id())
    return jsonify({**status_dict(_user_id()), "stopped": stopped})


@blueprint.post("/api/practice/commands")
@login_required
def command():  # type: ignore[no-untyped-def]
    """Runs one declarative command on the practice robot: {"command": {...}}."""
    received_at = time.perf_counter()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", 'Send a JSON object: {"command": {...}}.', "body")
    target = resolve_target(PRACTICE_TARGET, _user_id())
    try:
        parsed = parse_command(body.get("command"), skill_schemas(target.link))
    except CommandInvalid as invalid:
        raise ApiError(400, "invalid_field", invalid.message, invalid.field) from None
    except RobotUnavailable as error:
        raise ApiError(503, "robot_offline", f"{error} Try again in a moment.") from None
    return jsonify(execute(target, parsed, received_at)), 202


@blueprint.get("/api/robots/<target_name>/command-goals/<goal_id>")
@login_required
def goal(target_name: str, goal_id: str):  # type: ignore[no-untyped-def]
    """A goal of the practice robot ("practice") or of a lab robot the user controls."""
    if not GOAL_ID.fullmatch(goal_id):
        raise ApiError(404, "unknown_goal", "There is no goal with that id.", "goal_id")
    return jsonify({"goal": goal_state(resolve_target(target_name, _user_id()), goal_id)})


def camera_channel(ws) -> None:  # type: ignore[no-untyped-def]
    """The camera of the user's own practice robot."""
    if not current_user.is_authenticated:
        _refuse(ws, CLOSE_NOT_LOGGED_IN, "not_logged_in", "Your session has ended. Log in again.")
        return
    robot = practice_manager().get(_user_id())
    if robot is None:
        _refuse(ws, 4404, "no_practice_robot", "Start your practice robot first.")
        return
    relay_stream(ws, robot.link.camera)


sock.route("/ws/practice/camera", bp=blueprint)(camera_channel)
