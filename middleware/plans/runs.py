"""Running a stored plan on a robot: the user's practice robot ("Try on my practice robot") or a lab robot they
control now ("Run on lab-1"). The plan goes as one motor goal through access/commands.py, re-checked first against
the skills of the robot it runs on; the page follows the goal's channel for the line running and the robot's
telemetry for the trace.

The practice robot runs in the scene of the lab robot named beside it (restarted in that scene when it runs
another) and starts where that lab robot truly stands now (read server-side from one telemetry message, never sent
to the page), through PlaceRobot: where its camera shows it, among the obstacles it really has around it, not at
its odometry pose, which after minutes of driving may be a metre off and inside a crate. When the lab robot's
odometry is more than DRIFT_NOTED_M off, the start's sentence says so and names the ways back (localize it, or
return it to its dock), since a run on it then goes that far astray. Asked "from the dock", it is carried to its
dock instead, the scene's spawn pose, where a lab robot starts its day. When the lab robot does not answer, the
practice robot starts at its dock and the answer's start says why. Without a lab robot beside it, it starts where
it stands.

A practice robot that does not run yet (or runs another scene) is not started during the request: the run claims it
in the request's unit of work (PracticeManager.begin_start) and answers 202 with starting true and no goal; the
practice manager starts it once that is committed (the PendingStart the route hands to after_commit), GET
/api/practice says starting then running, and the run asked again runs the plan on it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy.orm import Session

from middleware.access.commands import Commander, robot_commands
from middleware.errors import ApiError, written_number
from middleware.plans.language import Plan, plan_from_json, plan_to_json
from middleware.plans.proto_form import plan_to_proto
from middleware.robots.link import CommandRefused, RobotUnavailable
from middleware.robots.messages import goal_dict
from middleware.teaching.practice_robots import PendingStart, practice_manager, practice_name
from middleware.teaching.targets import PRACTICE_TARGET, skill_schemas
from protos.telelab.v1 import robot_pb2


@dataclass(frozen=True)
class RunRequest:
    """What the user asked: where to run, beside which lab robot (practice only), and whether from the dock."""

    target: str
    beside: str | None
    from_dock: bool


def watchdog_lines(plan: Plan | Mapping[str, object]) -> list[int]:
    """The lines of the plan's `set watchdog` steps, blocks included: of a Plan, or of its canonical JSON as stored
    (read before any robot is asked for its skills, or started)."""
    document = plan_to_json(plan) if isinstance(plan, Plan) else plan
    found: list[int] = []
    pending = list(_steps_of(document.get("steps")))
    while pending:
        step = pending.pop()
        line = step.get("line")
        if step.get("kind") == "set" and step.get("setting") == "watchdog" and isinstance(line, int):
            found.append(line)
        for block in ("body", "then", "else"):
            pending.extend(_steps_of(step.get(block)))
    return sorted(found)


def _steps_of(value: object) -> list[Mapping[str, object]]:
    return [step for step in value if isinstance(step, Mapping)] if isinstance(value, list) else []


def check_settings_permitted(plan: Plan | Mapping[str, object], may_set_watchdog: bool) -> None:
    """403 not_permitted naming the first `set watchdog` line when the user may not set the robot's watchdog."""
    lines = [] if may_set_watchdog else watchdog_lines(plan)
    if lines:
        raise ApiError(403, "not_permitted", gettext(
            "Line %(line)s: your course does not let students set the watchdog (the time the base keeps a drive "
            "command); remove the line or ask your tutor to allow it on the course's page.", line=lines[0]),
            "watchdog_s")


@dataclass(frozen=True)
class LabRobotNow:
    """The lab robot beside the practice robot: its name, scene, where it truly stands (None when it did not
    answer) and how far its odometry is off that."""

    name: str
    scene: str | None
    pose: robot_pb2.Pose2D | None
    odometry_off_m: float = 0.0


def lab_robot_now(robot_name: str, user_id: int) -> LabRobotNow:
    """The scene a lab robot runs and where it truly stands, if it answers: a copy started there sees what its
    camera sees, where its drifted odometry may stand in a crate."""
    link = robot_commands().require(robot_name, user_id, field="beside")
    try:
        odometry, standing = link.poses_now()
        off_m = math.hypot(odometry.x_m - standing.x_m, odometry.y_m - standing.y_m)
        return LabRobotNow(robot_name, link.info(max_age_s=5.0).scene_name or None, standing, off_m)
    except RobotUnavailable:
        return LabRobotNow(robot_name, None, None)


DRIFT_NOTED_M = 0.2  # odometry further off than this is worth a sentence: the run on the lab robot will differ


def drift_note(beside: LabRobotNow) -> str:
    """Why a run on the drifted lab robot will not go where this one goes, and the ways back; "" when it will."""
    if beside.odometry_off_m < DRIFT_NOTED_M:
        return ""
    return " " + gettext("%(robot)s's odometry is %(off)s m off where it stands, so a run on it goes that far astray: "
                         "localize it (Localization on the console's Navigate tab) or return it to its dock first.",
                         robot=beside.name, off=written_number(beside.odometry_off_m, ".1f"))


def start_practice_robot(robot: Commander, from_dock: bool, beside: LabRobotNow | None) -> dict[str, object]:
    """Places the practice robot where its run starts; where that is ("lab_robot", "dock" or "here") and a
    sentence for the page."""
    if from_dock:
        robot.return_to_dock()
        return {"at": "dock", "message": gettext("Starts at its dock.")}
    if beside is None:
        return {"at": "here", "message": gettext("Starts where it stands.")}
    if beside.pose is None:
        reason = gettext("%(robot)s did not answer", robot=beside.name)
    else:
        pose = beside.pose
        try:
            robot.place_robot(pose)
            x_m, y_m = round(pose.x_m, 2) + 0.0, round(pose.y_m, 2) + 0.0  # + 0.0: no "-0.00"
            return {"at": "lab_robot", "message": gettext(
                "Starts where %(robot)s stands now (x %(x)s m, y %(y)s m).", robot=beside.name,
                x=written_number(x_m, ".2f"), y=written_number(y_m, ".2f")) + drift_note(beside)}
        except CommandRefused as refused:
            if refused.code != "invalid_field":
                raise
            reason = gettext("%(robot)s's pose is no place to stand (%(why)s)", robot=beside.name,
                             why=refused.message)
    robot.return_to_dock()
    return {"at": "dock", "message": gettext("Starts at its dock: %(reason)s.", reason=reason)}


@dataclass(frozen=True)
class PlanRun:
    """A run's answer for the page, and the practice robot's start to run once the request's claim is committed
    (None when the plan runs now)."""

    answer: dict[str, object]
    pending: PendingStart | None = None


def claim_practice_robot(session: Session, user_id: int, username: str, scene: str | None) -> PlanRun | None:
    """None when the user's practice robot runs (in scene, when one is asked); else its claim in session (the
    caller's unit of work) and the answer that it is starting."""
    manager = practice_manager()
    running = manager.get(user_id)
    if running is not None and (scene is None or manager.scene_of(running.name) == scene):
        return None
    pending = manager.begin_start(session, user_id, username, scene=scene)  # None: another start is under way
    name = pending.name if pending is not None else practice_name(username, user_id)
    return PlanRun({"robot": name, "practice": True, "starting": True, "start": None, "goal": None,
                    "status_url": "/api/practice"}, pending)


def run_plan(session: Session, user_id: int, username: str, name: str, document: dict[str, object],
             request: RunRequest, may_set_watchdog: bool) -> PlanRun:
    """Starts the plan on the requested robot: the goal, and where the page follows it and cancels it; or, when the
    practice robot must start first, its claim in session and an answer saying it is starting.
    A `set watchdog` line is refused (403) unless may_set_watchdog."""
    check_settings_permitted(document, may_set_watchdog)  # before a practice robot starts for a refused plan
    practice = request.target == PRACTICE_TARGET
    start: dict[str, object] | None = None
    beside: LabRobotNow | None = None
    if practice:
        beside = lab_robot_now(request.beside, user_id) if request.beside else None
        claimed = claim_practice_robot(session, user_id, username, beside.scene if beside else None)
        if claimed is not None:
            return claimed
        robot = robot_commands().for_user(practice_name(username, user_id), user_id, field="target")
    else:
        robot = robot_commands().for_user(request.target, user_id, field="target")
    plan = plan_from_json(document, skill_schemas(robot.link, motor_only=True))
    if practice:
        start = start_practice_robot(robot, request.from_dock, beside)
    goal = robot.run_plan(name, plan_to_proto(plan), preempt=True)
    answer = goal_dict(goal)
    goal_id = str(answer["goal_id"])
    robot_name = robot.robot_name
    return PlanRun({"robot": robot_name, "practice": practice, "starting": False, "start": start, "goal": answer,
                    "goal_channel": f"/ws/robots/{robot_name}/goals/{goal_id}",
                    "telemetry_channel": f"/ws/robots/{robot_name}/telemetry",
                    "cancel_url": f"/api/robots/{robot_name}/goals/{goal_id}",
                    "robot_url": f"/api/robots/{robot_name}"})
