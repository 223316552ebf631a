"""The console's descriptors and the skill API: activate, cancel and read goals; the map."""

from __future__ import annotations

import math

from flask import Blueprint, current_app, jsonify, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware import i18n
from middleware.access.commands import Commander, robot_commands
from middleware.api.contract import ANY, BOOLEAN, OBJECT, STRING, array, described, number, obj
from middleware.assessment.hidden_obstacles import MAP_REFUSAL, OBSTACLES_HIDDEN, hiding_book
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lab.panels import robot_panels
from middleware.lab.response_times import parse_report, record_report
from middleware.lab.schemas import GOAL_ID_PATTERN, NAME_PATTERN
from middleware.models import Role
from middleware.plans.services import console_skill_panels
from middleware.preferences.stored import chosen_camera_picture
from middleware.robots.catalog import CAMERA_PICTURES, camera_picture_of
from middleware.robots.link import CommandRefused, RobotUnavailable
from middleware.robots.messages import FINAL_GOAL_STATUSES, goal_dict, map_dict
from middleware.robots.registry import robot_registry

blueprint = Blueprint("skills", __name__)

MAX_PARAMETERS = 32
MAX_TEXT_VALUE = 64
SUPERVISOR_ROLES = (Role.TUTOR, Role.ADMIN)
ROBOT_SILENT = ("The robot does not answer, so its camera, sensors and skills cannot be listed: driving, the turn "
                "and chat are here; reload this page once it is back.")


def _user_id() -> int:
    return int(current_user.get_id())


def parse_activation(body: object) -> tuple[dict[str, object], bool]:
    """The parameters and the preempt flag of an activation request, checked for shape and finiteness."""
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object with 'parameters' and 'preempt'."), "body")
    parameters = body.get("parameters", {})
    preempt = body.get("preempt", False)
    if not isinstance(preempt, bool):
        raise ApiError(400, "invalid_field", gettext("preempt must be true or false."), "preempt")
    if not isinstance(parameters, dict) or len(parameters) > MAX_PARAMETERS:
        raise ApiError(400, "invalid_field", gettext("parameters must be an object of at most %(max_parameters)s "
                                                     "values.", max_parameters=MAX_PARAMETERS),
                       "parameters")
    for name, value in parameters.items():
        if not NAME_PATTERN.fullmatch(name):
            raise ApiError(400, "invalid_field", gettext("%(value)s is not a parameter name.", value=repr(name[:64])),
                                                 "parameters")
        if isinstance(value, float) and not math.isfinite(value):
            raise ApiError(400, "invalid_field", gettext("%(name)s must be a finite number.", name=name), name)
        if isinstance(value, str) and len(value) > MAX_TEXT_VALUE:
            raise ApiError(400, "invalid_field", gettext("%(name)s is too long.", name=name), name)
        if not isinstance(value, bool | int | float | str):
            raise ApiError(400, "invalid_field", gettext("%(name)s must be a number, true/false or a word.", name=name),
                                                 name)
    return parameters, preempt


@blueprint.get("/api/robots/<robot_name>/panels")
@login_required
@described(answers={200: obj(("robot",), robot=STRING, skills_available=BOOLEAN)})
def panels(robot_name: str) -> ResponseReturnValue:
    """The descriptors of every panel of the robot's console."""
    link = robot_commands().require(robot_name, _user_id())
    try:
        info, skills = link.info(refresh=True), link.skills(refresh=True)
    except RobotUnavailable:
        info, skills = None, None
    personal = robot_registry().is_personal_name(robot_name)
    kind, default_picture = camera_picture_of(get_session(), robot_name)
    chosen = chosen_camera_picture(get_session(), _user_id(), kind, CAMERA_PICTURES)
    panels = i18n.translate_panels(robot_panels(robot_name, info, skills, personal, (kind, default_picture), chosen))
    panels += console_skill_panels(get_session(), _user_id(), robot_name)  # the user's plans used as skills
    return jsonify({"robot": robot_name, "skills_available": skills is not None, "personal": personal,
                    "panels": panels, "notice": "" if info is not None else ROBOT_SILENT})


@blueprint.post("/api/robots/<robot_name>/skills/<skill>/goals")
@login_required
@described(
    body=obj(parameters=obj(description="name -> number, true/false or a word"), preempt=BOOLEAN),
    answers={202: obj(("goal",), goal=OBJECT)},
    refusals=(409, 503),
)
def activate(robot_name: str, skill: str) -> ResponseReturnValue:
    """Starts a skill as a goal for the controller."""
    robot = robot_commands().for_user(robot_name, _user_id())
    if not NAME_PATTERN.fullmatch(skill):
        raise ApiError(404, "unknown_skill", gettext("There is no skill by that name."), "skill")
    parameters, preempt = parse_activation(request.get_json(silent=True))
    goal = robot.activate(skill, parameters, preempt)
    return jsonify({"goal": goal_dict(goal), "robot_rtt_ms": _robot_leg_ms(robot)}), 202


def _robot_leg_ms(robot: Commander) -> float | None:
    """The middleware -> skill server time of the command robot just sent, for the console's response times."""
    spent_ms = robot.robot_round_trip_ms
    return None if spent_ms is None else round(spent_ms, 3)


@blueprint.put("/api/robots/<robot_name>/response-times")
@login_required
@described(body=obj(delivery=OBJECT, throughput_bps=ANY), answers={200: obj(("recorded",), recorded=BOOLEAN)})
def report_response_times(robot_name: str) -> ResponseReturnValue:
    """The console's response-time figures for the robot (its panel's table), kept for the user's tutor."""
    robot_commands().require(robot_name, _user_id())
    figures = parse_report(request.get_json(silent=True))
    record_report(get_session(), _user_id(), robot_name, figures)
    return jsonify({"recorded": True})


def _goal_id(goal_id: str) -> str:
    if not GOAL_ID_PATTERN.fullmatch(goal_id):
        raise ApiError(404, "unknown_goal", gettext("There is no goal with that id."), "goal_id")
    return goal_id


@blueprint.get("/api/robots/<robot_name>/goals")
@login_required
@described(answers={200: obj(("goals",), goals=array(OBJECT), robot_online=BOOLEAN)}, refusals=(503,))
def running_goals(robot_name: str) -> ResponseReturnValue:
    """The robot's running goals, whoever started them (a console opened again, a tour's step, another tab): its
    panels show them as their own. Observers may read them too; none while the robot does not answer."""
    link = robot_commands().require(robot_name, _user_id())
    try:
        goals = link.goals()
    except RobotUnavailable:
        return jsonify({"goals": [], "robot_online": False})
    running = [goal for goal in map(goal_dict, goals) if goal["status"] not in FINAL_GOAL_STATUSES]
    return jsonify({"goals": running, "robot_online": True})


@blueprint.get("/api/robots/<robot_name>/goals/<goal_id>")
@login_required
@described(answers={200: obj(("goal",), goal=OBJECT)}, refusals=(503,))
def goal(robot_name: str, goal_id: str) -> ResponseReturnValue:
    """A goal's state (observers may read it too)."""
    robot = robot_commands().for_user(robot_name, _user_id())
    state = robot.goal_state(_goal_id(goal_id))
    return jsonify({"goal": goal_dict(state)})


@blueprint.delete("/api/robots/<robot_name>/goals/<goal_id>")
@login_required
@described(answers={200: obj(("goal",), goal=OBJECT)}, refusals=(409, 503))
def cancel(robot_name: str, goal_id: str) -> ResponseReturnValue:
    """Cancels a goal; its message reports the error left."""
    robot = robot_commands().for_user(robot_name, _user_id())
    goal_id = _goal_id(goal_id)
    state = robot.cancel(goal_id)
    return jsonify({"goal": goal_dict(state)})


def _supervision(robot_name: str) -> Commander:
    """The user's supervisory actions on the robot (the controller's, or a tutor's or an admin's at any time)."""
    return robot_commands().for_supervision(robot_name, _user_id(), current_user.role in SUPERVISOR_ROLES)


@blueprint.delete("/api/robots/<robot_name>/map")
@login_required
@described(answers={200: obj(("map", "ended_goal_ids", "message"), map={"type": "null"},
                            ended_goal_ids=array(STRING), message=STRING)}, refusals=(409, 503))
def clear_map(robot_name: str) -> ResponseReturnValue:
    """Forgets the robot's map (supervisory): a map gone wrong would otherwise mislead every later user."""
    robot = _supervision(robot_name)
    ended = robot.clear_map()
    return jsonify({"map": None, "ended_goal_ids": ended,
                    "message": gettext("The map was cleared. Activate Environment modelling to build a new one.")})


@blueprint.post("/api/robots/<robot_name>/dock")
@login_required
@described(answers={200: obj(("ended_goal_ids", "dock", "message"), ended_goal_ids=array(STRING),
                            dock=obj(("x_m", "y_m", "theta_rad"), x_m=number(), y_m=number(), theta_rad=number()),
                            message=STRING)}, refusals=(409, 503))
def return_to_dock(robot_name: str) -> ResponseReturnValue:
    """Carries the robot back to its dock (supervisory): the way out of a drifted pose or a robot stuck on a wall."""
    robot = _supervision(robot_name)
    answer = robot.return_to_dock()
    dock = answer.dock
    return jsonify({"ended_goal_ids": list(answer.ended_goal_ids),
                    "dock": {"x_m": dock.x_m, "y_m": dock.y_m, "theta_rad": dock.theta_rad},
                    "message": gettext("The robot is back at its dock; its odometry restarts there. The map "
                                       "was kept.")})


@blueprint.get("/api/robots/<robot_name>/map")
@login_required
@described(answers={200: obj(("map",), map=ANY)}, refusals=(503,))
def occupancy_map(robot_name: str) -> ResponseReturnValue:
    """The occupancy grid built by environment modelling so far, or {"map": null} with a sentence before any.

    Having no map yet is the normal state of a fresh robot, not a missing resource, so it is no 404. During the
    user's obstacle-zone test it is refused: environment modelling may have drawn the floor plan into it.
    """
    link = robot_commands().require(robot_name, _user_id())
    if hiding_book(current_app).hides(_user_id(), get_session()):
        raise ApiError(403, OBSTACLES_HIDDEN, gettext(MAP_REFUSAL))
    try:
        grid = link.get_map()
    except CommandRefused as refused:
        if refused.reason != "not_possible_now":
            raise
        return jsonify({"map": None, "message": gettext("No map yet: activate Environment modelling to build one.")})
    return jsonify({"map": map_dict(grid)})
