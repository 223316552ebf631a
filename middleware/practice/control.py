"""Running a declarative command (lesson cue, tour step) on a robot the user may command, with its timings.

A target is the user's practice robot or a lab robot whose control they hold now; both obey only a token.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from middleware.errors import ApiError
from middleware.lessons.commands import RobotCommand
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.messages import goal_dict, parameter_schema_dict

PRACTICE_TARGET = "practice"
MAX_DRIVE_HOLD_S = 10.0  # direct_control's own limit; a longer drive cue is renewed by the page


@dataclass(frozen=True)
class CommandTarget:
    """A robot and the token under which this user may command it now."""

    name: str
    link: RobotLink
    token: str
    next_sequence: Callable[[], int]


def skill_schemas(link: RobotLink) -> dict[str, list[dict[str, object]]]:
    """The robot's skills and their parameter schemas, as commands.parse_command takes them."""
    return {s.name: [parameter_schema_dict(p) for p in s.parameters] for s in link.skills()}


def resolve_target(target: object, user_id: int) -> CommandTarget:
    """The practice robot of user_id ("practice") or a lab robot they control; an ApiError otherwise."""
    from middleware.access.coordinator import access_coordinator
    from middleware.practice.manager import practice_manager
    from middleware.robots.registry import robot_registry

    if target == PRACTICE_TARGET:
        robot = practice_manager().get(user_id)
        if robot is None:
            raise ApiError(409, "no_practice_robot", "Start your practice robot first.", "target")
        return CommandTarget(robot.name, robot.link, robot.token, robot.next_sequence)
    if not isinstance(target, str) or not 0 < len(target) <= 64:
        raise ApiError(400, "invalid_field", 'target must be "practice" or a lab robot\'s name.', "target")
    link = robot_registry().get(target)
    if link is None:
        raise ApiError(404, "unknown_robot", f"There is no robot named {target!r}.", "target")
    token = access_coordinator().controller_token(target, user_id)
    if token is None:
        raise ApiError(403, "not_controller", "You do not control this robot now: use your practice robot, "
                                              "or wait for your turn.", "target")
    return CommandTarget(target, link, token, lambda: link.reserve_sequences() + 1)


def execute(target: CommandTarget, command: RobotCommand, received_at: float,
            hold_s: float = MAX_DRIVE_HOLD_S) -> dict[str, object]:
    """Sends command; the answer has the goal (if any) and the middleware-to-ack time in ms.

    A drive becomes a direct_control goal held for hold_s (at most 10 s), so it stops by itself if the page
    goes away; a stop is a zero drive, which preempts any motor goal at once.
    """
    try:
        if command.kind == "stop":
            result = target.link.drive(target.token, target.next_sequence(), 0.0, 0.0)
            goal = None
            acked_at = time.perf_counter()
            applied: object = result.applied_sequence
        else:
            if command.kind == "drive":
                hold = min(MAX_DRIVE_HOLD_S, max(0.1, hold_s))
                state = target.link.activate_skill(target.token, "direct_control", {
                    "linear_mps": command.linear_mps, "angular_radps": command.angular_radps,
                    "duration_s": round(hold, 3)}, preempt=True)
            else:
                state = target.link.activate_skill(target.token, command.skill, dict(command.parameters),
                                                   preempt=True)
            acked_at = time.perf_counter()
            goal = goal_dict(state)
            applied = None
    except CommandRefused as refused:
        status = {"not_found": 404, "not_controller": 403, "unauthenticated": 403, "not_possible_now": 409}
        raise ApiError(status.get(refused.code, 400), refused.code, refused.message, refused.field) from None
    except RobotUnavailable as error:
        raise ApiError(503, "robot_offline", f"{error} Try again in a moment.") from None
    return {"robot": target.name, "command": command.to_dict(), "goal": goal, "applied_sequence": applied,
            "middleware_to_ack_ms": round((acked_at - received_at) * 1000, 3),
            "acked_unix_ms": round(time.time() * 1000, 3)}


def goal_state(target: CommandTarget, goal_id: str) -> dict[str, object]:
    """A goal's state on target."""
    try:
        return goal_dict(target.link.get_goal(goal_id))
    except CommandRefused:
        raise ApiError(404, "unknown_goal", "There is no goal with that id.", "goal_id") from None
    except RobotUnavailable as error:
        raise ApiError(503, "robot_offline", f"{error} Try again in a moment.") from None


def reference_skills(user_id: int | None = None) -> dict[str, list[dict[str, object]]]:
    """The skill schemas to check lessons and tours against: the user's practice robot, else any lab robot."""
    from middleware.practice.manager import practice_manager
    from middleware.robots.registry import robot_registry

    links: list[RobotLink] = []
    if user_id is not None and (robot := practice_manager().get(user_id)) is not None:
        links.append(robot.link)
    registry = robot_registry()
    links += [link for name in registry.names() if (link := registry.get(name)) is not None]
    for link in links:
        try:
            return skill_schemas(link)
        except RobotUnavailable:
            continue
    raise ApiError(503, "no_robot_to_check", "No robot answers now, so the skills cannot be checked. "
                                             "Start your practice robot or try again in a moment.")
