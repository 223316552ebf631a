"""Running a declarative command (lesson cue, tour step) on a robot the user may command, with its timings.

A target is the user's practice robot or a lab robot; every command goes through access/commands.py.
"""

from __future__ import annotations

import time

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.access.commands import MAX_DRIVE_HOLD_S, Commander, robot_commands
from middleware.api.contract import OBJECT, STRING, nullable, number, obj, whole
from middleware.errors import ApiError
from middleware.robots.link import RobotLink, RobotUnavailable
from middleware.robots.messages import goal_dict, parameter_schema_dict
from middleware.robots.registry import robot_registry
from middleware.teaching.command_form import RobotCommand
from middleware.teaching.practice_robots import practice_manager
from protos.telelab.v1 import robot_pb2

PRACTICE_TARGET = "practice"


def skill_schemas(link: RobotLink, motor_only: bool = False) -> dict[str, list[dict[str, object]]]:
    """The robot's skills and their parameter schemas, as command_form.parse_command takes them (motor_only: the
    skills that drive the wheels, the only ones a plan runs)."""
    return {s.name: [parameter_schema_dict(p) for p in s.parameters] for s in link.skills()
            if s.motor or not motor_only}


def resolve_target(target: object, user_id: int) -> Commander:
    """The user's commands to their practice robot ("practice") or to a lab robot; an ApiError naming target
    otherwise. Whether they control the robot is the command path's question, asked when a command goes."""
    if target == PRACTICE_TARGET:
        robot = practice_manager().get(user_id)
        if robot is None:
            raise ApiError(409, "no_practice_robot", gettext("Start your practice robot first."), "target")
        target = robot.name
    if not isinstance(target, str) or not 0 < len(target) <= 64:
        raise ApiError(400, "invalid_field", gettext("target must be \"practice\" or a lab robot's name."), "target")
    return robot_commands().for_user(target, user_id, field="target")


# execute's answer, as a route's contract says it: the goal started (none for a stop) and the time to the ack.
COMMAND_ANSWER = obj(("robot", "command", "goal", "applied_sequence", "middleware_to_ack_ms", "acked_unix_ms"),
                     robot=STRING, command=OBJECT, goal=nullable(OBJECT), applied_sequence=nullable(whole()),
                     middleware_to_ack_ms=number(), acked_unix_ms=number())


def execute(robot: Commander, command: RobotCommand, received_at: float,
            hold_s: float = MAX_DRIVE_HOLD_S) -> dict[str, object]:
    """Sends command; the answer has the goal (if any) and the middleware-to-ack time in ms.

    A drive becomes a held drive (a direct_control goal of at most 10 s), so it stops by itself if the page
    goes away; a stop is a zero drive, which preempts any motor goal at once.
    """
    goal: dict[str, object] | None = None
    applied: int | None = None
    if command.kind == "stop":
        applied = robot.stop().applied_sequence
    elif command.kind == "drive":
        goal = goal_dict(robot.hold_drive(command.linear_mps, command.angular_radps, hold_s))
    else:
        goal = goal_dict(robot.activate(command.skill, dict(command.parameters), preempt=True))
    acked_at = time.perf_counter()
    return {"robot": robot.robot_name, "command": command.to_dict(), "goal": goal, "applied_sequence": applied,
            "middleware_to_ack_ms": round((acked_at - received_at) * 1000, 3),
            "acked_unix_ms": round(time.time() * 1000, 3)}


def goal_state(robot: Commander, goal_id: str) -> dict[str, object]:
    """A goal's state on the robot."""
    return goal_dict(robot.goal_state(goal_id))


def _reference_links(user_id: int | None) -> list[RobotLink]:
    """The robots authoring forms ask: the user's practice robot first, then every lab robot."""
    links: list[RobotLink] = []
    if user_id is not None and (robot := practice_manager().get(user_id)) is not None:
        links.append(robot.link)
    registry = robot_registry()
    return links + [link for name in registry.names() if (link := registry.get(name)) is not None]


def reference_info(user_id: int | None = None) -> robot_pb2.RobotInfo | None:
    """The description (with its panels) of the first robot that answers among _reference_links, else None."""
    for link in _reference_links(user_id):
        try:
            return link.info()
        except RobotUnavailable:
            continue
    return None


def reference_catalog(user_id: int | None = None) -> list[dict[str, object]]:
    """The skills lessons and tours are written for, with titles and parameter schemas, for the authoring forms:
    the user's practice robot's, else any lab robot's."""
    for link in _reference_links(user_id):
        try:
            return [{"name": s.name, "title": s.title, "help": s.help, "direct_drive": s.direct_drive,
                     "motor": s.motor, "parameters": [parameter_schema_dict(p) for p in s.parameters]}
                    for s in link.skills()]
        except RobotUnavailable:
            continue
    raise ApiError(503, "no_robot_to_check", gettext("No robot answers now, so the skills cannot be checked. Start "
                                                     "your practice robot or try again in a moment."))


def authoring_catalog(user_id: int | None = None) -> list[dict[str, object]] | None:
    """reference_catalog for an editor page, or None when no robot answers (the page says so)."""
    try:
        return reference_catalog(user_id)
    except ApiError:
        return None


def reference_skills(user_id: int | None = None, motor_only: bool = False) -> dict[str, list[dict[str, object]]]:
    """The skill schemas to check lessons and tours against (see reference_catalog); motor_only: plans'."""
    return {str(entry["name"]): entry["parameters"] for entry in reference_catalog(user_id)  # type: ignore[misc]
            if entry["motor"] or not motor_only}
