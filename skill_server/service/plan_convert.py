"""RunPlan's request as the robot core's Plan: shapes only (a step without a kind, a parameter without a value
are refused here, naming the line); limits and schemas are the core's to check (skill_server/plans/validation.py)."""

from __future__ import annotations

from protos.telelab.v1 import robot_pb2
from skill_server.robot import (
    DriveLine,
    IfLine,
    InvalidPlan,
    OnLine,
    Plan,
    PlanCondition,
    PlanError,
    PlanLine,
    RepeatLine,
    SayLine,
    SetLine,
    SkillLine,
    WaitLine,
)


def plan_from_proto(request: robot_pb2.RunPlanRequest) -> Plan:
    """The plan of a RunPlan request, or InvalidPlan naming every step whose shape is wrong."""
    faults: list[PlanError] = []
    plan = Plan(request.name, _block(request.plan, faults))
    if faults:
        raise InvalidPlan(faults)
    return plan


def _block(block: robot_pb2.PlanBlock, faults: list[PlanError]) -> tuple[PlanLine, ...]:
    lines = (_line(step, faults) for step in block.steps)
    return tuple(line for line in lines if line is not None)


def _line(step: robot_pb2.PlanStep, faults: list[PlanError]) -> PlanLine | None:
    at = (int(step.line), int(step.column))
    kind = step.WhichOneof("kind")
    if kind == "skill":
        parameters = []
        for name, value in sorted(step.skill.parameters.items()):
            which = value.WhichOneof("kind")
            if which is None:
                faults.append(PlanError(*at, name, f"{name} has no value"))
            else:
                parameters.append((name, getattr(value, which)))
        return SkillLine(*at, step.skill.skill, tuple(parameters), step.skill.duration_s)
    if kind == "drive":
        return DriveLine(*at, step.drive.linear_mps, step.drive.angular_radps, step.drive.duration_s)
    if kind == "wait":
        return WaitLine(*at, _condition(step.wait, "condition"), step.wait.duration_s)
    if kind == "repeat":
        return RepeatLine(*at, int(step.repeat.count), _block(step.repeat.body, faults))
    if kind == "branch":
        return IfLine(*at, _condition(step.branch, "condition"), _block(step.branch.then_block, faults),
                      _block(step.branch.else_block, faults))
    if kind == "set":
        return SetLine(*at, step.set.setting, step.set.value)
    if kind == "say":
        return SayLine(*at, step.say.text)
    if kind == "on":
        return OnLine(*at, step.on.event, step.on.value, _block(step.on.body, faults))
    faults.append(PlanError(*at, "kind", "the step has no kind (skill, drive, wait, repeat, branch, set, say or on)"))
    return None


def _condition(holder: robot_pb2.WaitStep | robot_pb2.IfStep, field: str) -> PlanCondition | None:
    if not holder.HasField(field):
        return None
    condition = holder.condition
    return PlanCondition(condition.kind, condition.value, condition.negate)
