"""Running a stored plan on a robot: the user's practice robot ("Try on my practice robot") or a lab robot they
control now ("Run on lab-1"). The plan goes as one motor goal through access/commands.py, re-checked first against
the skills of the robot it runs on; the page follows the goal's channel for the line running and the robot's
telemetry for the trace.

The practice robot runs in the scene of the lab robot named beside it (restarted in that scene when it runs
another), and may be carried to its dock first, the scene's spawn pose, where a lab robot starts its day. It is
not placed at the lab robot's current pose: no RPC places a robot anywhere but at its dock.
"""

from __future__ import annotations

from dataclasses import dataclass

from middleware.access.commands import Commander, refusal_error, robot_commands
from middleware.plans.language import plan_from_json
from middleware.plans.proto_form import plan_to_proto
from middleware.robots.link import CommandRefused, RobotUnavailable
from middleware.robots.messages import goal_dict
from middleware.teaching.practice_robots import practice_manager
from middleware.teaching.targets import PRACTICE_TARGET, skill_schemas


@dataclass(frozen=True)
class RunRequest:
    """What the user asked: where to run, beside which lab robot (practice only), and whether from the dock."""

    target: str
    beside: str | None
    from_dock: bool


def lab_scene(robot_name: str, user_id: int) -> str | None:
    """The scene a lab robot runs, if it answers (None otherwise: the practice robot keeps its own)."""
    link = robot_commands().require(robot_name, user_id, field="beside")
    try:
        return link.info(max_age_s=5.0).scene_name or None
    except RobotUnavailable:
        return None


def practice_commander(user_id: int, username: str, scene: str | None) -> Commander:
    """The user's practice robot, started (or restarted) in scene when it is not running there."""
    manager = practice_manager()
    running = manager.get(user_id)
    if running is not None and scene is not None and manager.scene_of(running.name) != scene:
        manager.stop(user_id)
        running = None
    if running is None:
        running = manager.start(user_id, username, scene=scene)
    return robot_commands().for_user(running.name, user_id, field="target")


def run_plan(user_id: int, username: str, name: str, document: dict[str, object], request: RunRequest
             ) -> dict[str, object]:
    """Starts the plan on the requested robot; the goal, and where the page follows it and cancels it."""
    if request.target == PRACTICE_TARGET:
        scene = lab_scene(request.beside, user_id) if request.beside else None
        robot = practice_commander(user_id, username, scene)
    else:
        robot = robot_commands().for_user(request.target, user_id, field="target")
    try:
        plan = plan_from_json(document, skill_schemas(robot.link, motor_only=True))
        if request.from_dock and request.target == PRACTICE_TARGET:
            robot.return_to_dock()
        goal = robot.run_plan(name, plan_to_proto(plan), preempt=True)
    except (CommandRefused, RobotUnavailable) as error:
        raise refusal_error(error) from None
    answer = goal_dict(goal)
    goal_id = str(answer["goal_id"])
    robot_name = robot.robot_name
    return {"robot": robot_name, "practice": request.target == PRACTICE_TARGET, "goal": answer,
            "goal_channel": f"/ws/robots/{robot_name}/goals/{goal_id}",
            "telemetry_channel": f"/ws/robots/{robot_name}/telemetry",
            "cancel_url": f"/api/robots/{robot_name}/goals/{goal_id}",
            "robot_url": f"/api/robots/{robot_name}"}
