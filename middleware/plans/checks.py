"""The checks both forms of a plan share: skills and their parameters, drives, conditions, settings, durations,
texts, units, and the limits of the plan as a whole. A failed check raises StepProblem; the reader of the text or
the JSON adds where it is."""

from __future__ import annotations

import difflib
import math
import unicodedata
from collections.abc import Mapping, Sequence

from babel.numbers import format_decimal
from flask_babel import get_locale, gettext, lazy_gettext  # type: ignore[import-untyped]

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
# what a unit measures, as a sentence names it with its article (each whole, so a translation agrees with it)
MEASURE_NAMES = {"distance": lazy_gettext("a distance"), "time": lazy_gettext("a time"),
                 "angle": lazy_gettext("an angle"), "speed": lazy_gettext("a speed"),
                 "turn rate": lazy_gettext("a turn rate")}
_BIDI_CONTROLS = frozenset("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u200e\u200f")


class StepProblem(Exception):
    """A check that failed: field is relative to the step ("parameters.goal_x_m"; "" for the step itself)."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field, self.message = field, message


def shown(value: object) -> str:
    """A value as a sentence quotes it, cut short (true, false and numbers as the plan writes them)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int):
        return str(value) if abs(value) < 10**30 else gettext("a number too large")
    if isinstance(value, str):
        return repr(value[:40] + ("..." if len(value) > 40 else ""))
    if value is None:
        return gettext("nothing")
    if isinstance(value, list):
        return gettext("a list")
    return gettext("an object") if isinstance(value, dict) else type(value).__name__


def grouped(number: float) -> str:
    """A count or a size as a sentence writes it, whole: 10,000 in English, 10.000 in Spanish (the plan's own
    numbers, quoted from what the user wrote, keep the point the plan language writes them with)."""
    locale = get_locale()
    if locale is None or locale.language == "en":
        return f"{number:,.0f}"
    return str(format_decimal(round(number), "#,##0", locale=locale))


def listed(names: Sequence[str]) -> str:
    """Names of the plan language (code, never translated) as a list, or "none"."""
    return ", ".join(names) or gettext("none")


def cut(written: str) -> str:
    """What the user wrote, cut short for a sentence."""
    return written if len(written) <= 40 else written[:37] + "..."


def character_problem(character: str) -> str | None:
    """Why a character may not stand in a plan's text, or None when it may."""
    category = unicodedata.category(character)
    if character == "\t":
        return None
    if category == "Cc" or category == "Cs" or character in _BIDI_CONTROLS or category in {"Zl", "Zp"}:
        return gettext("the invisible character %(code)s is not allowed; delete it", code=f"U+{ord(character):04X}")
    return None


def text_character_problem(character: str) -> str | None:
    """Why a character may not stand in a quoted text (a tab neither), or None."""
    if character == "\t":
        return gettext("a tab is not allowed; write spaces")
    return character_problem(character)


def text_problem(text: str) -> str | None:
    """Why a text (a say, a word) cannot be used, or None."""
    for character in text:
        problem = text_character_problem(character)
        if problem:
            return problem
    return None


def _checked(name: str, value: object, schema: Mapping[str, object], field: str, written: str | None) -> object:
    try:
        return check_parameter(name, value, schema)  # its sentence in the reader's language, as the plan's
    except CommandInvalid as invalid:
        got = cut(written) if written else shown(value)
        bounds = _out_of_range(value, schema)
        if bounds is not None:  # one sentence of the plan's, its numbers with the point the plan writes them with
            low, high = bounds
            unit = str(schema.get("unit") or "")
            if unit:
                raise StepProblem(field, gettext("%(field)s must be between %(low)s and %(high)s %(unit)s; got "
                                                 "%(value)s.", field=name, low=low, high=high, unit=unit,
                                                 value=got)) from None
            raise StepProblem(field, gettext("%(field)s must be between %(low)s and %(high)s; got %(value)s.",
                                             field=name, low=low, high=high, value=got)) from None
        message = invalid.message.rstrip(".").replace(f"parameters.{name}", name)
        raise StepProblem(field, gettext("%(problem)s; got %(written)s.", problem=message, written=got)) from None


def _out_of_range(value: object, schema: Mapping[str, object]) -> tuple[str, str] | None:
    """The range (as the plan writes numbers) a number broke that is otherwise what the schema takes, or None."""
    kind = schema.get("type")
    if kind not in {"double", "int"} or isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    if not math.isfinite(number) or (kind == "int" and not number.is_integer()):
        return None
    low, high = float(schema.get("minimum", -math.inf)), float(schema.get("maximum", math.inf))  # type: ignore[arg-type]
    if not (low or high) or low <= number <= high:
        return None
    return f"{low:g}", f"{high:g}"


def convert_unit(number: float, unit: str, wanted: str, name: str, written: str) -> float:
    """number written with unit, in the unit wanted (the parameter's); a unit measuring something else is refused."""
    if not unit:
        return number
    if unit not in UNITS:
        raise StepProblem("", gettext("%(written)s: %(unit)s is not a unit; use m, cm, s, ms, deg, rad, m/s, rad/s or "
                                      "deg/s.", written=cut(written), unit=repr(unit[:20])))
    measure, factor = UNITS[unit]
    wanted_measure = UNITS.get(wanted, ("", 1.0))[0]
    if not wanted_measure:
        raise StepProblem("", gettext("%(name)s takes a plain number, without a unit; got %(written)s.", name=name,
                                      written=cut(written)))
    if measure != wanted_measure:
        fitting = ", ".join(u for u, (m, _) in UNITS.items() if m == wanted_measure)
        raise StepProblem("", gettext("%(name)s is %(wanted)s in %(unit)s; %(written)s is %(measure)s. Use "
                                      "%(fitting)s.", name=name, wanted=str(MEASURE_NAMES[wanted_measure]),
                                      unit=wanted, written=cut(written), measure=str(MEASURE_NAMES[measure]),
                                      fitting=fitting))
    return number / _DIVISORS[unit] if unit in _DIVISORS else number * factor


def skill_schema(skill: str, skills: SkillSchemas) -> dict[str, Mapping[str, object]]:
    """The skill's parameters by name, or a StepProblem naming the skills the robot has."""
    if not SKILL_NAME.fullmatch(skill) or skill not in skills:
        raise StepProblem("skill", gettext("No skill %(skill)s that a plan can run%(hint)s; a plan runs the skills "
                                           "that drive the wheels: %(skills)s.", skill=shown(skill),
                                           hint=did_you_mean(skill, skills), skills=listed(sorted(skills))))
    return {str(p.get("name")): p for p in skills[skill]}


def did_you_mean(word: str, known: Sequence[str] | Mapping[str, object]) -> str:
    """ (did you mean go_to?) when a known word is close; names are lower case, so GO_TO is close to go_to. The hint
    is a parenthesis of its own that the sentences quote (their msgids show where: %(hint)s)."""
    if len(word) > 64:
        return ""
    lower = {name.lower(): name for name in known}
    if word.lower() in lower:
        return " " + gettext("(did you mean %(name)s? names are written in lower case)", name=lower[word.lower()])
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.75)
    return " " + gettext("(did you mean %(name)s?)", name=close[0]) if close else ""


def skill_parameter(skill: str, schema: Mapping[str, Mapping[str, object]], name: str, value: object,
                    written: str | None = None) -> object:
    """One parameter of a skill checked against its schema, as command_form checks a command's."""
    field = f"parameters.{name}" if SKILL_NAME.fullmatch(name) else "parameters"
    if name not in schema:
        short = {parameter.rpartition("_")[0] or parameter: parameter for parameter in schema}
        close = difflib.get_close_matches(name[:64], [*schema, *short], n=1, cutoff=0.75)
        hint = " " + gettext("(did you mean %(name)s?)", name=short.get(close[0], close[0])) if close else ""
        raise StepProblem(field, gettext("%(skill)s has no parameter %(name)s%(hint)s; it has %(parameters)s.",
                                         skill=skill, name=shown(name), hint=hint, parameters=listed(list(schema))))
    checked = _checked(name, value, schema[name], field, written)
    problem = text_problem(checked) if isinstance(checked, str) else None
    if problem:
        raise StepProblem(field, gettext("in %(name)s, %(problem)s.", name=name, problem=problem))
    return checked


def duration(value: object, field: str = "duration_s", written: str | None = None) -> float:
    """A duration: a finite number of seconds above 0 and at most 600."""
    number = _checked("duration_s", value, {"type": "double"}, field, written)
    assert isinstance(number, float)
    if not 0.0 < number <= MAX_STEP_DURATION_S:
        raise StepProblem(field, gettext("A duration must be more than 0 s and at most %(max)s s; got %(written)s.",
                                         max=f"{MAX_STEP_DURATION_S:g}",
                                         written=cut(written) if written else shown(value)))
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
        raise StepProblem("kind", gettext("%(kind)s is not a condition%(hint)s; use %(kinds)s.", kind=shown(kind),
                                          hint=did_you_mean(kind, CONDITION_KINDS), kinds=", ".join(CONDITION_KINDS)))
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
            raise StepProblem("value", gettext("%(name)s takes no value; got %(written)s.", name=kind,
                                               written=cut(written) if written else shown(value)))
        return Condition(kind, None, negate)
    if value is None:
        example = "0.5" if kind == "obstacle_within" else "0.2"
        raise StepProblem("value", gettext("%(kind)s needs a value, as in %(example)s.", kind=kind,
                                           example=f"{kind} {example}"))
    checked = _checked(kind, value, schema, "value", written)
    assert isinstance(checked, float)
    return Condition(kind, checked, negate)


def event_schema(event: str) -> Mapping[str, object] | None:
    """The schema of an event's value (None: the event takes none), or a StepProblem for an unknown event."""
    if event not in EVENTS:
        raise StepProblem("event", gettext("%(event)s is not an event%(hint)s; use %(events)s.", event=shown(event),
                                           hint=did_you_mean(event, EVENTS), events=", ".join(EVENTS)))
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
        raise StepProblem("value", gettext("%(name)s takes no value; got %(written)s.", name=event,
                                           written=cut(written) if written else shown(value)))
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
                errors.append(place_error(step.line, step.column, where, gettext(
                    "an on block cannot hold another on: while an on block runs, no event is handled.")))
            if step.event in handled:
                errors.append(place_error(step.line, step.column, f"{where}.event", gettext(
                    "%(event)s is handled already on line %(line)s of this block; write one on for it.",
                    event=step.event, line=handled[step.event])))
            handled.setdefault(step.event, step.line)
            if index == len(steps) - 1:
                errors.append(place_error(step.line, step.column, where, gettext(
                    "this on handles nothing: it watches the lines after it in its block, and none follows. Put it "
                    "before them.")))
            if not step.body:
                errors.append(place_error(step.line, step.column, f"{where}.body", gettext(
                    "this on has nothing in its block.")))
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
        raise StepProblem("setting", gettext("%(setting)s is not a setting%(hint)s; use %(settings)s.",
                                             setting=shown(setting), hint=did_you_mean(setting, SETTINGS),
                                             settings=", ".join(SETTINGS)))
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
        raise StepProblem("text", gettext("say needs some text in quotes, as in say \"hello\"."))
    if len(value) > MAX_SAY_CHARS:
        raise StepProblem("text", gettext("A say text has at most %(max)s characters; this one has %(count)s.",
                                          max=MAX_SAY_CHARS, count=len(value)))
    problem = text_problem(value)
    if problem:
        raise StepProblem("text", gettext("In the text, %(problem)s.", problem=problem))
    return value


def plan_totals(steps: Sequence[Step], path: str = "steps") -> list[PlanError]:
    """The limits of the plan as a whole: steps multiplied out, and the time it takes at the least."""
    errors: list[PlanError] = []
    if not steps:
        return [place_error(0, 0, "steps", gettext(
            "The plan is empty: write at least one command, such as say \"hello\"."))]
    count, certain = 0, 0.0
    for index, step in enumerate(steps):
        count += expanded_count((step,))
        if count > MAX_EXPANDED_STEPS:
            errors.append(place_error(step.line, step.column, f"{path}[{index}]",
                                      gettext("With repeats multiplied out the plan has more than %(max)s steps "
                                              "by here (%(count)s); repeat less.", max=grouped(MAX_EXPANDED_STEPS),
                                              count=grouped(count))))
            break
    for index, step in enumerate(steps):
        certain += certain_duration_s((step,))
        if certain > MAX_PLAN_DURATION_S:
            errors.append(place_error(step.line, step.column, f"{path}[{index}]",
                                      gettext("By here the plan takes at least %(seconds)s s of drives and "
                                              "waits; a plan may run at most %(max)s s.", seconds=grouped(certain),
                                              max=grouped(MAX_PLAN_DURATION_S))))
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
    """A PlanError whose sentence starts with where it is: "line 3, column 9: ...", or the field without a line.
    message is said already in the reader's language (gettext: English outside a request)."""
    if message[:1].isupper() and not message[1:2].isupper():  # "A plan ..." but not "URL ..."
        message = message[0].lower() + message[1:]
    if line > 0 and column > 0:
        said = gettext("line %(line)s, column %(column)s: %(problem)s", line=line, column=column, problem=message)
    elif line > 0:
        said = gettext("line %(line)s: %(problem)s", line=line, problem=message)
    else:
        said = gettext("%(field)s: %(problem)s", field=field, problem=message)
    return PlanError(line, column, field, said)
