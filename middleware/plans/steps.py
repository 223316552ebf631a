"""A checked plan as data: its steps, conditions and errors, and the limits every plan keeps.

Pure values, no parsing: middleware.plans.language builds them from text or JSON and writes them back.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from flask_babel import gettext, ngettext  # type: ignore[import-untyped]

from middleware.errors import Refused

FORMAT = "telelab-plan/1"
MAX_TEXT_BYTES = 65_536
MAX_LINES = 500
MAX_STEPS = 500  # steps as written (a JSON plan has no lines to count)
MAX_SAY_CHARS = 200
MAX_DEPTH = 8  # blocks inside blocks
MIN_REPEAT, MAX_REPEAT = 1, 100
MAX_EXPANDED_STEPS = 10_000  # repeats multiplied out, both branches of an if counted
MAX_STEP_DURATION_S = 600.0
MAX_PLAN_DURATION_S = 1_800.0  # the skill server ends a plan running longer (ABORTED TIMEOUT)
MAX_ERRORS = 50  # reported at most; a plan this broken is better rewritten than listed
PLAN_NAME_CHARACTERS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-")
MAX_PLAN_NAME = 64

CONDITION_KINDS = ("obstacle_within", "goal_reached", "battery_below", "line_seen")
SETTINGS = ("max_speed", "max_turn_rate", "watchdog")
# The events an on block reacts to (issue 33; the skill server's EVENTS in skill_server/plans/validation.py):
# obstacle_detected (detect_obstacle's rule; value: warning distance, m), wall_lost (wall_following), goal_reached
# (a skill line reached its goal), localized (the localization skill, run beside the plan), battery_low (value:
# fraction of full).
EVENTS = ("obstacle_detected", "wall_lost", "goal_reached", "localized", "battery_low")


@dataclass(frozen=True)
class PlanError:
    """One problem in a plan: where it is (1-based; 0 when the plan has no position for it), the field as a JSON
    path into the canonical form ("steps[2].count"), and a sentence that starts with the place."""

    line: int
    column: int
    field: str
    message: str

    def to_dict(self) -> dict[str, object]:
        """The error as JSON."""
        return {"line": self.line, "column": self.column, "field": self.field, "message": self.message}


class PlanInvalid(Refused, ValueError):
    """A plan that cannot be run (400 invalid_plan) with every problem found; field is the first one's."""

    def __init__(self, errors: tuple[PlanError, ...] | list[PlanError]) -> None:
        self.errors = tuple(errors)
        first = self.errors[0] if self.errors else PlanError(0, 0, "plan", gettext("The plan is not valid."))
        more = len(self.errors) - 1
        message = first.message if more <= 0 else ngettext("%(first)s (and %(num)s more problem)",
                                                           "%(first)s (and %(num)s more problems)", more,
                                                           first=first.message)
        super().__init__(400, "invalid_plan", message, first.field)

    def to_dict(self) -> dict[str, object]:
        """The JSON body of the error, with every problem under "errors"."""
        body = super().to_dict()
        body["errors"] = [error.to_dict() for error in self.errors]
        return body


@dataclass(frozen=True)
class Condition:
    """What a wait or an if tests: obstacle_within (metres), goal_reached (no value), battery_below (fraction),
    line_seen (no value: the line sensor sees the tape)."""

    kind: str
    value: float | None = None
    negate: bool = False


# line and column are where a step stands in the text; they do not take part in equality, so a plan written back
# as text and read again is equal to itself.


@dataclass(frozen=True)
class SkillStep:
    """A skill run to its end, or for duration_s and then ended without failing."""

    skill: str
    parameters: tuple[tuple[str, object], ...] = ()
    duration_s: float | None = None
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class DriveStep:
    """Wheel velocities held for a time."""

    linear_mps: float
    angular_radps: float
    duration_s: float
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class WaitStep:
    """Standing still until the condition holds (at most duration_s when both are given), or for duration_s."""

    condition: Condition | None
    duration_s: float | None
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class RepeatStep:
    """The body, count times."""

    count: int
    body: tuple[Step, ...]
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class IfStep:
    """then when the condition holds, otherwise the else block (possibly empty)."""

    condition: Condition
    then: tuple[Step, ...]
    otherwise: tuple[Step, ...] = ()
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class SetStep:
    """A setting for the rest of the plan: max_speed (m/s), max_turn_rate (rad/s) or watchdog (s)."""

    setting: str
    value: float
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class SayStep:
    """A message to the people watching."""

    text: str
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


@dataclass(frozen=True)
class OnStep:
    """From the next line to the end of its block, when event happens the line running is cut short and body runs
    in its place; value is the event's threshold (None: its default)."""

    event: str
    value: float | None
    body: tuple[Step, ...]
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)


Step = SkillStep | DriveStep | WaitStep | RepeatStep | IfStep | SetStep | SayStep | OnStep


@dataclass(frozen=True)
class Plan:
    """A checked plan: every parameter within its skill's schema, every limit kept."""

    steps: tuple[Step, ...]


def is_plan_name(name: object) -> bool:
    """Whether name can name a plan (the goal is "plan:<name>"): 1 to 64 letters, digits, - and _."""
    return isinstance(name, str) and 0 < len(name) <= MAX_PLAN_NAME and set(name) <= PLAN_NAME_CHARACTERS
