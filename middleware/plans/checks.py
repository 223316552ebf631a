"""The checks both forms of a plan share: skills and their parameters, drives, conditions, settings, durations,
texts, units, and the limits of the plan as a whole. A failed check raises StepProblem; the reader of the text or
the JSON adds where it is."""

from __future__ import annotations

import difflib
import math
import unicodedata
from collections.abc import Mapping, Sequence

from middleware.plans.steps import (
    CONDITION_KINDS,
    EVENTS,
    MAX_ERRORS,
    MAX_EXPANDED_STEPS,
    MAX_PLAN_DURATION_S,
    MAX_REPEAT,
    MAX_SAY_CHARS,
    MAX_STEP_DURATION_S,
    MIN_REPEAT,
    SETTINGS,
    Condition,
    IfStep,
    OnStep,
    PlanError,
    RepeatStep,
    Step,
)
from middleware.plans.summary import certain_duration_s, expanded_count
from middleware.teaching.command_form import (
    MAX_ANGULAR_RADPS,
    MAX_LINEAR_MPS,
    SKILL_NAME,
    CommandInvalid,
    SkillSchemas,
    check_parameter,
)

DIRECT_CONTROL = "direct_control"  # its schema gives the robot's velocity ceilings for drive and set
MAX_PARAMETERS = 32
OBSTACLE_RANGE_M = (0.05, 8.0)  # the laser's reach
BATTERY_RANGE = (0.01, 1.0)  # a fraction of full; below 0 is never true, and the skill server refuses 0
WARNING_RANGE_M = (0.05, 3.0)  # detect_obstacle's warning distance (its schema on the skill server)
WATCHDOG_RANGE_S = (0.2, 5.0)  # the base's drive watchdog: what SetLimits accepts (README, Low-level commands)
MIN_SPEED_MPS, MIN_TURN_RATE_RADPS = 0.05, 0.1

# unit -> (what it measures, factor to the base unit); a value's unit must measure what its parameter measures
UNITS: dict[str, tuple[str, float]] = {
    "m": ("distance", 1.0), "cm": ("distance", 0.01), "s": ("time", 1.0), "ms": ("time", 0.001),
    "rad": ("angle", 1.0), "deg": ("angle", math.pi / 180.0), "m/s": ("speed", 1.0),
    "rad/s": ("turn rate", 1.0), "deg/s": ("turn rate", math.pi / 180.0),
}
_DIVISORS = {"cm": 100.0, "ms": 1000.0}  # divided rather than multiplied, so 40cm is exactly 0.4
_UNIT_LIST = "m, cm, s, ms, deg, rad, m/s, rad/s or deg/s"
TAB_IN_TEXT = "a tab is not allowed; write spaces"
_BIDI_CONTROLS = frozenset("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u200e\u200f")


class StepProblem(Exception):
    """A check that failed: field is relative to the step ("parameters.goal_x_m"; "" for the step itself)."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field, self.message = field, message


def shown(value: object) -> str:
    """A value as a sentence quotes it, cut short."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int):
        return str(value) if abs(value) < 10**30 else "a number too large"
    if isinstance(value, str):
        return repr(value[:40] + ("..." if len(value) > 40 else ""))
    if value is None:
        return "nothing"
    return "a list" if isinstance(value, list) else ("an object" if isinstance(value, dict) else type(value).__name__)


def cut(written: str) -> str:
    """What the user wrote, cut short for a sentence."""
    return written if len(written) <= 40 else written[:37] + "..."


def character_problem(character: str) -> str | None:
    """Why a character may not stand in a plan's text, or None when it may."""
    category = unicodedata.category(character)
    if character == "\t":
        return None
    if category == "Cc" or category == "Cs" or character in _BIDI_CONTROLS or category in {"Zl", "Zp"}:
        return f"the invisible character U+{ord(character):04X} is not allowed; delete it"
    return None


def text_problem(text: str) -> str | None:
    """Why a text (a say, a word) cannot be used, or None."""
    for character in text:
        problem = character_problem(character) or (TAB_IN_TEXT if character == "\t" else None)
        if problem:
            return problem
    return None


def _checked(name: str, value: object, schema: Mapping[str, object], field: str, written: str | None) -> object:
    try:
        return check_parameter(name, value, schema)
    except CommandInvalid as invalid:
        message = invalid.message.rstrip(".").replace(f"parameters.{name}", name)
        raise StepProblem(field, f"{message}; got {cut(written) if written else shown(value)}.") from None


def convert_unit(number: float, unit: str, wanted: str, name: str, written: str) -> float:
    """number written with unit, in the unit wanted (the parameter's); a unit measuring something else is refused."""
    if not unit:
        return number
    if unit not in UNITS:
        raise StepProblem("", f"{cut(written)}: {unit[:20]!r} is not a unit; use {_UNIT_LIST}.")
    measure, factor = UNITS[unit]
    wanted_measure = UNITS.get(wanted, ("", 1.0))[0]
    if not wanted_measure:
        raise StepProblem("", f"{name} takes a plain number, without a unit; got {cut(written)}.")
    if measure != wanted_measure:
        fitting = ", ".join(u for u, (m, _) in UNITS.items() if m == wanted_measure)
        raise StepProblem("", f"{name} is {_a(wanted_measure)} in {wanted}; {cut(written)} is {_a(measure)}. "
                              f"Use {fitting}.")
    return number / _DIVISORS[unit] if unit in _DIVISORS else number * factor


def _a(noun: str) -> str:
    return f"an {noun}" if noun[:1] in "aeiou" else f"a {noun}"


def skill_schema(skill: str, skills: SkillSchemas) -> dict[str, Mapping[str, object]]:
    """The skill's parameters by name, or a StepProblem naming the skills the robot has."""
    if not SKILL_NAME.fullmatch(skill) or skill not in skills:
        raise StepProblem("skill", f"No skill {shown(skill)} that a plan can run{did_you_mean(skill, skills)}; a plan "
                                   f"runs the skills that drive the wheels: {', '.join(sorted(skills)) or 'none'}.")
    return {str(p.get("name")): p for p in skills[skill]}


def did_you_mean(word: str, known: Sequence[str] | Mapping[str, object]) -> str:
    """ (did you mean go_to?) when a known word is close; names are lower case, so GO_TO is close to go_to."""
    if len(word) > 64:
        return ""
    lower = {name.lower(): name for name in known}
    if word.lower() in lower:
        return f" (did you mean {lower[word.lower()]}? names are written in lower case)"
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.75)
    return f" (did you mean {close[0]}?)" if close else ""


def skill_parameter(skill: str, schema: Mapping[str, Mapping[str, object]], name: str, value: object,
                    written: str | None = None) -> object:
    """One parameter of a skill checked against its schema, as command_form checks a command's."""
    field = f"parameters.{name}" if SKILL_NAME.fullmatch(name) else "parameters"
    if name not in schema:
        short = {parameter.rpartition("_")[0] or parameter: parameter for parameter in schema}
        close = difflib.get_close_matches(name[:64], [*schema, *short], n=1, cutoff=0.75)
        hint = f" (did you mean {short.get(close[0], close[0])}?)" if close else ""
        raise StepProblem(field, f"{skill} has no parameter {shown(name)}{hint}; "
                                 f"it has {', '.join(schema) or 'none'}.")
    checked = _checked(name, value, schema[name], field, written)
    problem = text_problem(checked) if isinstance(checked, str) else None
    if problem:
        raise StepProblem(field, f"in {name}, {problem}.")
    return checked


def duration(value: object, field: str = "duration_s", written: str | None = None) -> float:
    """A duration: a finite number of seconds above 0 and at most 600."""
    number = _checked("duration_s", value, {"type": "double"}, field, written)
    assert isinstance(number, float)
    if not 0.0 < number <= MAX_STEP_DURATION_S:
        raise StepProblem(field, f"A duration must be more than 0 s and at most {MAX_STEP_DURATION_S:g} s; "
                                 f"got {cut(written) if written else shown(value)}.")
    return number


def velocity_schemas(skills: SkillSchemas) -> tuple[Mapping[str, object], Mapping[str, object]]:
    """The linear and angular velocity schemas: the robot's direct_control ones, else the command form's ceilings."""
    own = {str(p.get("name")): p for p in skills.get(DIRECT_CONTROL, ())}
    linear = own.get("linear_mps") or {"type": "double", "unit": "m/s", "minimum": -MAX_LINEAR_MPS,
                                       "maximum": MAX_LINEAR_MPS}
    angular = own.get("angular_radps") or {"type": "double", "unit": "rad/s", "minimum": -MAX_ANGULAR_RADPS,
                                           "maximum": MAX_ANGULAR_RADPS}
    return linear, angular


def drive_value(name: str, value: object, skills: SkillSchemas, written: str | None = None) -> float:
    """linear_mps or angular_radps of a drive, within the robot's ceilings."""
    linear, angular = velocity_schemas(skills)
    checked = _checked(name, value, linear if name == "linear_mps" else angular, name, written)
    assert isinstance(checked, float)
    return checked


def condition_schema(kind: str) -> Mapping[str, object] | None:
    """The schema of a condition's value (None: the condition takes none), or a StepProblem for an unknown kind."""
    if kind not in CONDITION_KINDS:
        raise StepProblem("kind", f"{shown(kind)} is not a condition{did_you_mean(kind, CONDITION_KINDS)}; "
                                  f"use {', '.join(CONDITION_KINDS)}.")
    if kind == "obstacle_within":
        return {"type": "double", "unit": "m", "minimum": OBSTACLE_RANGE_M[0], "maximum": OBSTACLE_RANGE_M[1]}
    if kind == "battery_below":
        return {"type": "double", "unit": "", "minimum": BATTERY_RANGE[0], "maximum": BATTERY_RANGE[1]}
    return None


def condition(kind: str, value: object, negate: bool, written: str | None = None) -> Condition:
    """A checked condition; value is None for goal_reached."""
    schema = condition_schema(kind)
    if schema is None:
        if value is not None:
            raise StepProblem("value", f"{kind} takes no value; got {cut(written) if written else shown(value)}.")
        return Condition(kind, None, negate)
    if value is None:
        example = "0.5" if kind == "obstacle_within" else "0.2"
        raise StepProblem("value", f"{kind} needs a value, as in {kind} {example}.")
    checked = _checked(kind, value, schema, "value", written)
    assert isinstance(checked, float)
    return Condition(kind, checked, negate)


def event_schema(event: str) -> Mapping[str, object] | None:
    """The schema of an event's value (None: the event takes none), or a StepProblem for an unknown event."""
    if event not in EVENTS:
        raise StepProblem("event", f"{shown(event)} is not an event{did_you_mean(event, EVENTS)}; "
                                   f"use {', '.join(EVENTS)}.")
    if event == "obstacle_detected":
        return {"type": "double", "unit": "m", "minimum": WARNING_RANGE_M[0], "maximum": WARNING_RANGE_M[1]}
    if event == "battery_low":
        return {"type": "double", "unit": "", "minimum": BATTERY_RANGE[0], "maximum": BATTERY_RANGE[1]}
    return None


def event_value(event: str, value: object, written: str | None = None) -> float | None:
    """A checked event and its value (None: the event's default)."""
    schema = event_schema(event)
    if value is None:
        return None
    if schema is None:
        raise StepProblem("value", f"{event} takes no value; got {cut(written) if written else shown(value)}.")
    checked = _checked(event, value, schema, "value", written)
    assert isinstance(checked, float)
    return checked


def handler_errors(steps: Sequence[Step], path: str = "steps", in_handler: bool = False) -> list[PlanError]:
    """The rules of on blocks: each watches lines after it in its block, one per event in a block, none in another's
    body, a body not empty."""
    errors: list[PlanError] = []
    handled: dict[str, int] = {}
    for index, step in enumerate(steps):
        where = f"{path}[{index}]"
        if isinstance(step, OnStep):
            if in_handler:
                errors.append(place_error(step.line, step.column, where, "an on block cannot hold another on: while "
                                                                         "an on block runs, no event is handled."))
            if step.event in handled:
                errors.append(place_error(step.line, step.column, f"{where}.event", f"{step.event} is handled "
                                          f"already on line {handled[step.event]} of this block; write one on "
                                          "for it."))
            handled.setdefault(step.event, step.line)
            if index == len(steps) - 1:
                errors.append(place_error(step.line, step.column, where, "this on handles nothing: it watches the "
                                          "lines after it in its block, and none follows. Put it before them."))
            if not step.body:
                errors.append(place_error(step.line, step.column, f"{where}.body", "this on has nothing in its "
                                                                                   "block."))
            errors += handler_errors(step.body, f"{where}.body", True)
        elif isinstance(step, RepeatStep):
            errors += handler_errors(step.body, f"{where}.body", in_handler)
        elif isinstance(step, IfStep):
            errors += handler_errors(step.then, f"{where}.then", in_handler)
            errors += handler_errors(step.otherwise, f"{where}.else", in_handler)
    return errors


def setting_schema(setting: str, skills: SkillSchemas) -> Mapping[str, object]:
    """What a setting accepts, or a StepProblem for an unknown one."""
    if setting not in SETTINGS:
        raise StepProblem("setting", f"{shown(setting)} is not a setting{did_you_mean(setting, SETTINGS)}; "
                                     f"use {', '.join(SETTINGS)}.")
    linear, angular = velocity_schemas(skills)
    if setting == "max_speed":
        return {"type": "double", "unit": "m/s", "minimum": MIN_SPEED_MPS,
                "maximum": linear.get("maximum", MAX_LINEAR_MPS)}
    if setting == "max_turn_rate":
        return {"type": "double", "unit": "rad/s", "minimum": MIN_TURN_RATE_RADPS,
                "maximum": angular.get("maximum", MAX_ANGULAR_RADPS)}
    return {"type": "double", "unit": "s", "minimum": WATCHDOG_RANGE_S[0], "maximum": WATCHDOG_RANGE_S[1]}


def setting_value(setting: str, value: object, skills: SkillSchemas, written: str | None = None) -> float:
    """A setting's value within its range."""
    checked = _checked(setting, value, setting_schema(setting, skills), "value", written)
    assert isinstance(checked, float)
    return checked


def repeat_count(value: object, written: str | None = None) -> int:
    """A repeat's count: a whole number from 1 to 100."""
    checked = _checked("count", value, {"type": "int", "minimum": MIN_REPEAT, "maximum": MAX_REPEAT}, "count",
                       written)
    assert isinstance(checked, int)
    return checked


def say_text(value: object) -> str:
    """A say's text: 1 to 200 characters, nothing invisible."""
    if not isinstance(value, str) or not value.strip():
        raise StepProblem("text", "say needs some text in quotes, as in say \"hello\".")
    if len(value) > MAX_SAY_CHARS:
        raise StepProblem("text", f"A say text has at most {MAX_SAY_CHARS} characters; this one has {len(value)}.")
    problem = text_problem(value)
    if problem:
        raise StepProblem("text", f"In the text, {problem}.")
    return value


def plan_totals(steps: Sequence[Step], path: str = "steps") -> list[PlanError]:
    """The limits of the plan as a whole: steps multiplied out, and the time it takes at the least."""
    errors: list[PlanError] = []
    if not steps:
        return [place_error(0, 0, "steps", "The plan is empty: write at least one command, such as say \"hello\".")]
    count, certain = 0, 0.0
    for index, step in enumerate(steps):
        count += expanded_count((step,))
        if count > MAX_EXPANDED_STEPS:
            errors.append(place_error(step.line, step.column, f"{path}[{index}]",
                                f"With repeats multiplied out the plan has more than {MAX_EXPANDED_STEPS:,} steps "
                                f"by here ({count:,}); repeat less."))
            break
    for index, step in enumerate(steps):
        certain += certain_duration_s((step,))
        if certain > MAX_PLAN_DURATION_S:
            errors.append(place_error(step.line, step.column, f"{path}[{index}]",
                                f"By here the plan takes at least {certain:,.0f} s of drives and waits; a plan may "
                                f"run at most {MAX_PLAN_DURATION_S:,.0f} s."))
            break
    return errors


class TooManyErrors(Exception):
    """MAX_ERRORS problems are found: reading stops (a hostile plan costs no more than a bad one)."""


def add_error(errors: list[PlanError], error: PlanError) -> None:
    """Adds error; TooManyErrors once there are MAX_ERRORS."""
    errors.append(error)
    if len(errors) >= MAX_ERRORS:
        raise TooManyErrors()


def place_error(line: int, column: int, field: str, message: str) -> PlanError:
    """A PlanError whose sentence starts with where it is: "line 3, column 9: ...", or the field without a line."""
    where = (f"line {line}, column {column}" if column > 0 else f"line {line}") if line > 0 else field
    if message[:1].isupper() and not message[1:2].isupper():  # "A plan ..." but not "URL ..."
        message = message[0].lower() + message[1:]
    return PlanError(line, column, field, f"{where}: {message}")
