"""RunPlan's wire form becomes the core's Plan shape for shape: every step kind, lines and columns kept, and a
step without a kind or a parameter without a value refused naming its line."""

from __future__ import annotations

import pytest

from protos.telelab.v1 import robot_pb2
from skill_server.robot import (
    DriveLine,
    IfLine,
    InvalidPlan,
    Plan,
    PlanCondition,
    RepeatLine,
    SayLine,
    SetLine,
    SkillLine,
    WaitLine,
)
from skill_server.service.plan_convert import plan_from_proto

Step = robot_pb2.PlanStep


def request(*steps: robot_pb2.PlanStep) -> robot_pb2.RunPlanRequest:
    return robot_pb2.RunPlanRequest(token="t", name="wire", plan=robot_pb2.PlanBlock(steps=steps))


def test_every_step_kind_comes_across_with_its_line_and_column() -> None:
    near = robot_pb2.PlanCondition(kind="obstacle_within", value=0.5, negate=True)
    plan = plan_from_proto(request(
        Step(line=1, column=1, skill=robot_pb2.SkillStep(skill="wall_following", duration_s=20.0, parameters={
            "side": robot_pb2.ParameterValue(string_value="left"),
            "distance_m": robot_pb2.ParameterValue(double_value=0.4)})),
        Step(line=2, column=1, drive=robot_pb2.DriveStep(linear_mps=0.2, angular_radps=-0.1, duration_s=2.0)),
        Step(line=3, column=1, wait=robot_pb2.WaitStep(duration_s=2.0)),
        Step(line=4, column=1, wait=robot_pb2.WaitStep(condition=robot_pb2.PlanCondition(kind="goal_reached"))),
        Step(line=5, column=1, repeat=robot_pb2.RepeatStep(count=3, body=robot_pb2.PlanBlock(steps=[
            Step(line=6, column=3, say=robot_pb2.SayStep(text="again"))]))),
        Step(line=8, column=1, branch=robot_pb2.IfStep(condition=near, then_block=robot_pb2.PlanBlock(steps=[
            Step(line=9, column=3, set=robot_pb2.SetStep(setting="max_speed", value=0.3))]))),
    ))
    assert plan == Plan("wire", (
        SkillLine(1, 1, "wall_following", (("distance_m", 0.4), ("side", "left")), 20.0),
        DriveLine(2, 1, 0.2, -0.1, 2.0),
        WaitLine(3, 1, None, 2.0),
        WaitLine(4, 1, PlanCondition("goal_reached"), 0.0),
        RepeatLine(5, 1, 3, (SayLine(6, 3, "again"),)),
        IfLine(8, 1, PlanCondition("obstacle_within", 0.5, True), (SetLine(9, 3, "max_speed", 0.3),), ()),
    ))


def test_shape_faults_are_all_named_by_line() -> None:
    with pytest.raises(InvalidPlan) as refused:
        plan_from_proto(request(
            Step(line=1, column=1),
            Step(line=2, column=4, repeat=robot_pb2.RepeatStep(count=2, body=robot_pb2.PlanBlock(steps=[
                Step(line=3, column=5, skill=robot_pb2.SkillStep(skill="go_to_goal", parameters={
                    "goal_x_m": robot_pb2.ParameterValue()}))]))),
        ))
    assert [str(error) for error in refused.value.errors] == [
        "line 1, column 1: kind: the step has no kind (skill, drive, wait, repeat, branch, set, say or on)",
        "line 3, column 5: goal_x_m: goal_x_m has no value",
    ]
