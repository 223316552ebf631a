"""The console's descriptors and the skill API: activate, cancel and read goals; the map."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import TypeVar

from flask import Blueprint, jsonify, request
from flask_login import current_user, login_required

from middleware.access.coordinator import access_coordinator
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lab.panels import robot_panels
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.messages import goal_dict, map_dict
from middleware.robots.registry import robot_registry

T = TypeVar("T")
blueprint = Blueprint("skills", __name__)

NAME_PATTERN = re.compile(r"^[a-z][a-z0-9_]{0,63}$")
GOAL_ID_PATTERN = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
MAX_PARAMETERS = 32
MAX_TEXT_VALUE = 64
STATUS_OF_REFUSAL = {"invalid_field": 400, "not_found": 404, "not_controller": 403, "unauthenticated": 403,
                     "not_possible_now": 409}


def robot_link(robot_name: str) -> RobotLink:
    """The link to robot_name, or a 404 naming it."""
    link = robot_registry().get(robot_name)
    if link is None:
        raise ApiError(404, "unknown_robot", f"There is no robot named {robot_name!r}.", "robot_name")
    return link


def controller_token(robot_name: str, known: bool = False) -> str:
    """The current user's controller token (known: as this process last saw it), or a 403 saying they observe."""
    coordinator = access_coordinator()
    read = coordinator.known_controller_token if known else coordinator.controller_token
    token = read(robot_name, int(current_user.get_id()), get_session())
    if token is None:
        raise ApiError(403, "not_controller", "You are observing: skills run for the person whose turn it is.")
    return token


def as_controller(robot_name: str, call: Callable[[str], T]) -> T:
    """call(token) with the user's controller token, read from the database only when the robot refuses the
    token this process knows (the turn moved on elsewhere): saves a read on every skill request."""
    token = controller_token(robot_name, known=True)
    try:
        return call(token)
    except CommandRefused as refused:
        if refused.code != "not_controller":
            raise
        fresh = controller_token(robot_name)
        if fresh == token:
            raise
    return call(fresh)


def refusal(error: CommandRefused | RobotUnavailable, not_found_code: str = "unknown_skill") -> ApiError:
    """The API error for a robot's refusal or absence."""
    if isinstance(error, RobotUnavailable):
        return ApiError(503, "robot_offline", f"{error} Try again in a moment.")
    if error.code == "not_possible_now":
        return ApiError(409, "busy", error.message)
    code = not_found_code if error.code == "not_found" else error.code
    return ApiError(STATUS_OF_REFUSAL.get(error.code, 400), code, error.message, error.field)


def parse_activation(body: object) -> tuple[dict[str, object], bool]:
    """The parameters and the preempt flag of an activation request, checked for shape and finiteness."""
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", "Send a JSON object with 'parameters' and 'preempt'.", "body")
    parameters = body.get("parameters", {})
    preempt = body.get("preempt", False)
    if not isinstance(preempt, bool):
        raise ApiError(400, "invalid_field", "preempt must be true or false.", "preempt")
    if not isinstance(parameters, dict) or len(parameters) > MAX_PARAMETERS:
        raise ApiError(400, "invalid_field", f"parameters must be an object of at most {MAX_PARAMETERS} values.",
                       "parameters")
    for name, value in parameters.items():
        if not NAME_PATTERN.fullmatch(name):
            raise ApiError(400, "invalid_field", f"{name[:64]!r} is not a parameter name.", "parameters")
        if isinstance(value, float) and not math.isfinite(value):
            raise ApiError(400, "invalid_field", f"{name} must be a finite number.", name)
        if isinstance(value, str) and len(value) > MAX_TEXT_VALUE:
            raise ApiError(400, "invalid_field", f"{name} is too long.", name)
        if not isinstance(value, bool | int | float | str):
            raise ApiError(400, "invalid_field", f"{name} must be a number, true/false or a word.", name)
    return parameters, preempt


@blueprint.get("/api/robots/<robot_name>/panels")
@login_required
def panels(robot_name: str):  # type: ignore[no-untyped-def]
    """The descriptors of every panel of the robot's console."""
    link = robot_link(robot_name)
    try:
        skills = link.skills(refresh=True)
    except RobotUnavailable:
        skills = None
    personal = robot_registry().is_personal_name(robot_name)
    return jsonify({"robot": robot_name, "skills_available": skills is not None, "personal": personal,
                    "panels": robot_panels(robot_name, skills, personal)})


@blueprint.post("/api/robots/<robot_name>/skills/<skill>/goals")
@login_required
def activate(robot_name: str, skill: str):  # type: ignore[no-untyped-def]
    """Starts a skill as a goal for the controller."""
    link = robot_link(robot_name)
    if not NAME_PATTERN.fullmatch(skill):
        raise ApiError(404, "unknown_skill", "There is no skill by that name.", "skill")
    parameters, preempt = parse_activation(request.get_json(silent=True))
    try:
        goal = as_controller(robot_name, lambda token: link.activate_skill(token, skill, parameters, preempt))
    except (CommandRefused, RobotUnavailable) as error:
        raise refusal(error) from None
    return jsonify({"goal": goal_dict(goal)}), 202


def _goal_id(goal_id: str) -> str:
    if not GOAL_ID_PATTERN.fullmatch(goal_id):
        raise ApiError(404, "unknown_goal", "There is no goal with that id.", "goal_id")
    return goal_id


@blueprint.get("/api/robots/<robot_name>/goals/<goal_id>")
@login_required
def goal(robot_name: str, goal_id: str):  # type: ignore[no-untyped-def]
    """A goal's state (observers may read it too)."""
    link = robot_link(robot_name)
    try:
        state = link.get_goal(_goal_id(goal_id))
    except (CommandRefused, RobotUnavailable) as error:
        raise refusal(error, "unknown_goal") from None
    return jsonify({"goal": goal_dict(state)})


@blueprint.delete("/api/robots/<robot_name>/goals/<goal_id>")
@login_required
def cancel(robot_name: str, goal_id: str):  # type: ignore[no-untyped-def]
    """Cancels a goal; its message reports the error left."""
    link = robot_link(robot_name)
    goal_id = _goal_id(goal_id)
    try:
        state = as_controller(robot_name, lambda token: link.cancel_goal(token, goal_id))
    except (CommandRefused, RobotUnavailable) as error:
        raise refusal(error, "unknown_goal") from None
    return jsonify({"goal": goal_dict(state)})


@blueprint.get("/api/robots/<robot_name>/map")
@login_required
def occupancy_map(robot_name: str):  # type: ignore[no-untyped-def]
    """The occupancy grid built by environment modelling so far."""
    link = robot_link(robot_name)
    try:
        grid = link.get_map()
    except CommandRefused as error:
        if error.code == "not_possible_now":
            raise ApiError(404, "no_map", "No map yet: run environment modelling first.") from None
        raise refusal(error) from None
    except RobotUnavailable as error:
        raise refusal(error) from None
    return jsonify(map_dict(grid))
