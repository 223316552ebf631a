"""A plan as the skill server receives it: lines of skills, drives, waits, blocks, settings and messages.

Plain values, no rules: `validation.py` checks a plan against the robot's skills and limits, `executor.py` runs
a checked one. line and column are where a step stands in the plan's text (0 when it has none).
"""

from __future__ import annotations

from dataclasses import dataclass

from skill_server.errors import InvalidParameter

ParameterValue = float | int | bool | str


@dataclass(frozen=True)
class PlanCondition:
    """obstacle_within (metres), goal_reached (no value), battery_below (fraction) or line_seen (no value: a cell of
    the line sensor is over the tape), maybe negated."""

    kind: str
    value: float = 0.0
    negate: bool = False


@dataclass(frozen=True)
class SkillLine:
    """A skill run to its end, or for duration_s (0: until it ends) and then ended without failing."""

    line: int
    column: int
    skill: str
    parameters: tuple[tuple[str, object], ...] = ()
    duration_s: float = 0.0


@dataclass(frozen=True)
class DriveLine:
    """Wheel velocities held for duration_s."""

    line: int
    column: int
    linear_mps: float
    angular_radps: float
    duration_s: float


@dataclass(frozen=True)
class WaitLine:
    """Standing still until the condition holds, or for duration_s; with both, TIMEOUT when it does not hold."""

    line: int
    column: int
    condition: PlanCondition | None
    duration_s: float = 0.0


@dataclass(frozen=True)
class RepeatLine:
    """A block run count times."""

    line: int
    column: int
    count: int
    body: tuple[PlanLine, ...]


@dataclass(frozen=True)
class IfLine:
    """One of two blocks, chosen by a condition when the line is reached."""

    line: int
    column: int
    condition: PlanCondition | None
    then_block: tuple[PlanLine, ...]
    else_block: tuple[PlanLine, ...] = ()


@dataclass(frozen=True)
class SetLine:
    """A setting for the rest of the plan: max_speed (m/s), max_turn_rate (rad/s), watchdog (s)."""

    line: int
    column: int
    setting: str
    value: float


@dataclass(frozen=True)
class SayLine:
    """A message to the people watching."""

    line: int
    column: int
    text: str


@dataclass(frozen=True)
class OnLine:
    """A handler: from the next line to the end of its block, when event happens the line running is cut short,
    body runs, and the plan goes on with the line after the one cut short. value is the event's threshold (the
    warning distance of obstacle_detected, the charge of battery_low); 0 takes the event's default."""

    line: int
    column: int
    event: str
    value: float
    body: tuple[PlanLine, ...]


PlanLine = SkillLine | DriveLine | WaitLine | RepeatLine | IfLine | SetLine | SayLine | OnLine


@dataclass(frozen=True)
class Plan:
    """A named plan as received."""

    name: str
    steps: tuple[PlanLine, ...]


@dataclass(frozen=True)
class PlanError:
    """One fault of a plan, where it stands and in which field."""

    line: int
    column: int
    field: str
    message: str

    def __str__(self) -> str:
        where = f"line {self.line}, column {self.column}: " if self.line else ""
        return f"{where}{self.field}: {self.message}"


class InvalidPlan(InvalidParameter):
    """A plan refused before anything moved; every fault found, the first one's field as the field."""

    SHOWN = 20  # the status message names this many faults; the rest are counted

    def __init__(self, errors: list[PlanError]) -> None:
        assert errors
        shown = "; ".join(str(error) for error in errors[:self.SHOWN])
        more = f"; and {len(errors) - self.SHOWN} more" if len(errors) > self.SHOWN else ""
        super().__init__(errors[0].field, f"invalid plan: {shown}{more}")
        self.errors = tuple(errors)
