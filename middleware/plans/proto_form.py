"""A checked plan as the RunPlan request's PlanBlock (protos/telelab/v1/robot.proto), line and column carried into
every PlanStep so the skill server's feedback and errors can name them."""

from __future__ import annotations

from middleware.plans.steps import (
    Condition,
    DriveStep,
    IfStep,
    OnStep,
    Plan,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    Step,
    WaitStep,
)
from protos.telelab.v1 import robot_pb2


def plan_to_proto(plan: Plan) -> robot_pb2.PlanBlock:
    """The plan as the skill server runs it."""
    return _block(plan.steps)


def _block(steps: tuple[Step, ...]) -> robot_pb2.PlanBlock:
    return robot_pb2.PlanBlock(steps=[_step(step) for step in steps])


def parameter_value(value: object) -> robot_pb2.ParameterValue:
    """One checked parameter value as a ParameterValue (bool before int: a bool is an int in Python)."""
    if isinstance(value, bool):
        return robot_pb2.ParameterValue(bool_value=value)
    if isinstance(value, int):
        return robot_pb2.ParameterValue(int_value=value)
    if isinstance(value, str):
        return robot_pb2.ParameterValue(string_value=value)
    if isinstance(value, float):
        return robot_pb2.ParameterValue(double_value=value)
    raise TypeError(f"a checked plan holds no {type(value).__name__} parameter")


def _condition(condition: Condition) -> robot_pb2.PlanCondition:
    return robot_pb2.PlanCondition(kind=condition.kind, value=condition.value or 0.0, negate=condition.negate)


def _step(step: Step) -> robot_pb2.PlanStep:
    proto = robot_pb2.PlanStep(line=step.line, column=step.column)
    if isinstance(step, SkillStep):
        proto.skill.skill = step.skill
        for name, value in step.parameters:
            proto.skill.parameters[name].CopyFrom(parameter_value(value))
        proto.skill.duration_s = step.duration_s or 0.0
    elif isinstance(step, DriveStep):
        proto.drive.CopyFrom(robot_pb2.DriveStep(linear_mps=step.linear_mps, angular_radps=step.angular_radps,
                                                 duration_s=step.duration_s))
    elif isinstance(step, WaitStep):
        proto.wait.duration_s = step.duration_s or 0.0
        if step.condition is not None:
            proto.wait.condition.CopyFrom(_condition(step.condition))
    elif isinstance(step, RepeatStep):
        proto.repeat.count = step.count
        proto.repeat.body.CopyFrom(_block(step.body))
    elif isinstance(step, IfStep):
        proto.branch.condition.CopyFrom(_condition(step.condition))
        proto.branch.then_block.CopyFrom(_block(step.then))
        proto.branch.else_block.CopyFrom(_block(step.otherwise))
    elif isinstance(step, SetStep):
        proto.set.setting, proto.set.value = step.setting, step.value
    elif isinstance(step, SayStep):
        proto.say.text = step.text
    elif isinstance(step, OnStep):
        proto.on.event, proto.on.value = step.event, step.value or 0.0
        proto.on.body.CopyFrom(_block(step.body))
    return proto
