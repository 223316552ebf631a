"""Checks a plan before anything moves: limits on size, nesting and durations, finite numbers, and every skill
step's parameters against that skill's schema. Every fault is collected, each naming its line, column and field."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields, replace

from skill_server.errors import InvalidParameter, UnknownSkill
from skill_server.plans.model import (
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
from skill_server.sim.drive_gate import MAX_WATCHDOG_S, MIN_WATCHDOG_S
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import TickInput
from skill_server.skills.registry import SkillRegistry

# The same limits as the plan language's (middleware/plans/language.py): a plan refused there is refused here.
MAX_DEPTH = 8  # repeat and if blocks inside one another
MAX_REPEAT = 100
MAX_EXPANDED_STEPS = 10_000  # repeats multiplied out, both branches of an if counted
MAX_WRITTEN_STEPS = 10_000  # steps as written, blocks' included (the wire form may come from anywhere)
MAX_DURATION_S = 600.0
MAX_SAY_CHARS = 200
MAX_OBSTACLE_DISTANCE_M = 10.0
NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]{1,64}")
BATTERY_FIELD = "battery_charge"  # TickInput's battery reading, 0..1 of full
CONDITIONS = ("obstacle_within", "goal_reached", "battery_below", "line_seen")
SETTINGS = ("max_speed", "max_turn_rate", "watchdog")


@dataclass(frozen=True)
class PlanEvent:
    """An event a plan's `on` reacts to: the skill that publishes it (which the robot must have), and the range and
    default of its value (None: it takes none)."""

    name: str
    skill: str
    value_range: tuple[float, float] | None = None
    default: float = 0.0
    unit: str = ""


# The same events as the plan language's (middleware/plans/steps.py EVENTS).
EVENTS: dict[str, PlanEvent] = {event.name: event for event in (
    PlanEvent("obstacle_detected", "detect_obstacle", (0.05, 3.0), 0.4, "m"),  # detect_obstacle's warning distance
    PlanEvent("wall_lost", "wall_following"),
    PlanEvent("goal_reached", ""),
    PlanEvent("localized", "localization"),
    PlanEvent("battery_low", "", (0.01, 1.0), 0.2, "(a fraction of full)"),
)}


@dataclass(frozen=True)
class CheckedPlan:
    """A plan that passed every check; its skill steps carry their validated parameters, defaults filled in."""

    plan: Plan
    expanded_steps: int
    skills: tuple[str, ...]


def robot_has_battery() -> bool:
    """Whether the skills' tick input carries a battery reading (battery_below needs one)."""
    return BATTERY_FIELD in {f.name for f in fields(TickInput)}


class _Checker:
    def __init__(self, registry: SkillRegistry, spec: RobotSpec) -> None:
        self.registry = registry
        self.spec = spec
        self.errors: list[PlanError] = []
        self.written = 0
        self.skills: list[str] = []
        self.in_handler = False  # checking the body of an on

    def fault(self, step: PlanLine, field: str, message: str) -> None:
        self.errors.append(PlanError(step.line, step.column, field, message))

    def block(self, steps: tuple[PlanLine, ...], depth: int) -> tuple[tuple[PlanLine, ...], int]:
        """The block with checked steps, and its expanded step count."""
        checked: list[PlanLine] = []
        expanded = 0
        handled: dict[str, int] = {}  # the block's on lines by event
        for index, step in enumerate(steps):
            if isinstance(step, OnLine):
                if step.event in handled:
                    self.fault(step, "event", f"{step.event} is handled already on line {handled[step.event]} of "
                                              "this block")
                handled.setdefault(step.event, step.line)
                if index == len(steps) - 1:
                    self.fault(step, "on", "this on handles nothing: it watches the lines after it in its block, "
                                           "and none follows")
            self.written += 1
            if self.written > MAX_WRITTEN_STEPS:
                self.fault(step, "steps", f"a plan holds at most {MAX_WRITTEN_STEPS} steps")
                break
            step, count = self.step(step, depth)
            checked.append(step)
            expanded += count
        return tuple(checked), expanded

    def step(self, step: PlanLine, depth: int) -> tuple[PlanLine, int]:
        if isinstance(step, SkillLine):
            return self.skill(step), 1
        if isinstance(step, DriveLine):
            self.number(step, "linear_mps", step.linear_mps, -self.spec.max_linear_mps, self.spec.max_linear_mps,
                        "m/s")
            self.number(step, "angular_radps", step.angular_radps, -self.spec.max_angular_radps,
                        self.spec.max_angular_radps, "rad/s")
            self.duration(step, step.duration_s, required=True)
            return step, 1
        if isinstance(step, WaitLine):
            if step.condition is None and step.duration_s == 0:
                self.fault(step, "duration_s", "a wait needs a duration, a condition or both")
            self.duration(step, step.duration_s, required=False)
            if step.condition is not None:
                self.condition(step, step.condition)
            return step, 1
        if isinstance(step, (RepeatLine, IfLine, OnLine)) and depth >= MAX_DEPTH:
            self.fault(step, "depth", f"blocks nest at most {MAX_DEPTH} deep")
            return step, 0
        if isinstance(step, RepeatLine):
            if isinstance(step.count, bool) or not isinstance(step.count, int) or not 1 <= step.count <= MAX_REPEAT:
                self.fault(step, "count", f"count must be an integer between 1 and {MAX_REPEAT}; got {step.count}")
            body, expanded = self.block(step.body, depth + 1)
            return replace(step, body=body), expanded * max(1, min(int(step.count), MAX_REPEAT))
        if isinstance(step, IfLine):
            if step.condition is None:
                self.fault(step, "condition", "an if needs a condition")
            else:
                self.condition(step, step.condition)
            then_block, then_count = self.block(step.then_block, depth + 1)
            else_block, else_count = self.block(step.else_block, depth + 1)
            return replace(step, then_block=then_block, else_block=else_block), 1 + then_count + else_count
        if isinstance(step, OnLine):
            return self.handler(step, depth)
        if isinstance(step, SetLine):
            self.setting(step)
            return step, 1
        if isinstance(step, SayLine):
            if len(step.text) > MAX_SAY_CHARS:
                self.fault(step, "text", f"say at most {MAX_SAY_CHARS} characters; got {len(step.text)}")
            elif any(ord(ch) < 32 or ord(ch) == 127 for ch in step.text):
                self.fault(step, "text", "the text may not hold control characters (line breaks, tabs)")
            return step, 1
        raise TypeError(f"not a plan step: {step!r}")

    def skill(self, step: SkillLine) -> SkillLine:
        try:
            entry = self.registry.entry(step.skill)
        except UnknownSkill as unknown:
            self.fault(step, "skill", str(unknown))
            return step
        if not entry.motor:
            self.fault(step, "skill", f"{step.skill} is a perceptive skill; a plan runs motor skills only "
                                      "(activate it beside the plan)")
            return step
        self.duration(step, step.duration_s, required=False)
        values: dict[str, object] = {}
        for name, value in step.parameters:
            values[name] = value
        try:
            checked = entry.description.validate(values)
        except InvalidParameter as invalid:
            self.fault(step, invalid.field, invalid.message)
            return step
        self.skills.append(step.skill)
        return replace(step, parameters=tuple(checked.items()))

    def handler(self, step: OnLine, depth: int) -> tuple[PlanLine, int]:
        """An on line: a known event the robot can publish, its value in range, a body holding no on."""
        event = EVENTS.get(step.event)
        if self.in_handler:
            self.fault(step, "on", "an on block cannot hold another on: while a handler runs no event is handled")
        if event is None:
            self.fault(step, "event", f"the event must be one of: {', '.join(EVENTS)}; got {step.event!r}")
        elif event.skill and event.skill not in {entry.description.name for entry in self.registry.entries()}:
            self.fault(step, "event", f"{step.event} comes from the {event.skill} skill, which this robot does not "
                                      "have")
        elif event.name == "battery_low" and not robot_has_battery():
            self.fault(step, "event", "this robot reports no battery; battery_low cannot happen")
        elif event.value_range is None:
            if step.value != 0:
                self.fault(step, "value", f"{step.event} takes no value; got {step.value}")
        elif step.value != 0:
            self.number(step, "value", step.value, event.value_range[0], event.value_range[1], event.unit)
        if not step.body:
            self.fault(step, "body", "an on block needs at least one line")
        outer, self.in_handler = self.in_handler, True
        body, expanded = self.block(step.body, depth + 1)
        self.in_handler = outer
        return replace(step, body=body), 1 + expanded

    def condition(self, step: PlanLine, condition: PlanCondition) -> None:
        if condition.kind not in CONDITIONS:
            self.fault(step, "condition.kind", f"the condition must be one of: {', '.join(CONDITIONS)}; "
                                               f"got {condition.kind!r}")
        elif condition.kind == "obstacle_within":
            self.number(step, "condition.value", condition.value, 0.0, MAX_OBSTACLE_DISTANCE_M, "m", above=True)
        elif condition.kind == "battery_below":
            if not robot_has_battery():
                self.fault(step, "condition.kind", "this robot reports no battery yet; battery_below cannot be "
                                                   "checked")
            else:
                self.number(step, "condition.value", condition.value, 0.0, 1.0, "(a fraction of full)", above=True)

    def setting(self, step: SetLine) -> None:
        ceilings = {"max_speed": (self.spec.max_linear_mps, "m/s"),
                    "max_turn_rate": (self.spec.max_angular_radps, "rad/s"), "watchdog": (MAX_WATCHDOG_S, "s")}
        if step.setting not in ceilings:
            self.fault(step, "setting", f"the setting must be one of: {', '.join(SETTINGS)}; got {step.setting!r}")
            return
        ceiling, unit = ceilings[step.setting]
        if step.setting == "watchdog":  # the base's drive watchdog: the range SetLimits accepts
            self.number(step, "value", step.value, MIN_WATCHDOG_S, ceiling, unit)
        else:
            self.number(step, "value", step.value, 0.0, ceiling, unit, above=True)

    def duration(self, step: PlanLine, duration_s: float, *, required: bool) -> None:
        if duration_s == 0 and not required:
            return
        self.number(step, "duration_s", duration_s, 0.0, MAX_DURATION_S, "s", above=True)

    def number(self, step: PlanLine, field: str, value: float, low: float, high: float, unit: str,
               above: bool = False) -> None:
        """Finite and within [low, high] (or (low, high] when above)."""
        ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
              and (low < value if above else low <= value) and value <= high)
        if not ok:
            lower = f"above {low:g}" if above else f"at least {low:g}"
            self.fault(step, field, f"{field} must be a finite number {lower} and at most {high:g} {unit}; "
                                    f"got {value}")


def check_plan(plan: Plan, registry: SkillRegistry, spec: RobotSpec) -> CheckedPlan:
    """The plan with validated skill parameters, or InvalidPlan naming every fault (nothing runs then)."""
    checker = _Checker(registry, spec)
    if not isinstance(plan.name, str) or not NAME_PATTERN.fullmatch(plan.name):
        checker.errors.append(PlanError(0, 0, "name", "the plan's name must be 1 to 64 letters, digits, - or _"))
    if not plan.steps:
        checker.errors.append(PlanError(0, 0, "steps", "the plan has no steps"))
    steps, expanded = checker.block(plan.steps, 0)
    if expanded > MAX_EXPANDED_STEPS:
        first = plan.steps[0]
        checker.errors.append(PlanError(first.line, first.column, "steps",
                                        f"the plan expands to {expanded} steps (repeats multiplied out, both "
                                        f"branches of each if counted); at most {MAX_EXPANDED_STEPS}"))
    if checker.errors:
        raise InvalidPlan(checker.errors)
    return CheckedPlan(replace(plan, steps=steps), expanded, tuple(dict.fromkeys(checker.skills)))
