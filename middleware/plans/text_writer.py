"""A plan written as text that reads back to an equal plan: one command a line, blocks indented, numbers written
so that they read back to the same float, short commands (go_to, turn_to, follow_wall) where they fit."""

from __future__ import annotations

import math

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.plans.aliases import ALIAS_OF_SKILL, ALIASES
from middleware.plans.checks import grouped, place_error
from middleware.plans.steps import (
    MAX_LINES,
    MAX_TEXT_BYTES,
    Condition,
    DriveStep,
    IfStep,
    OnStep,
    Plan,
    PlanError,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    Step,
    WaitStep,
)

INDENT = "  "
_WORD_START = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ_")
_WORD = _WORD_START | frozenset("0123456789")
_KEYWORDS = frozenset({"true", "false", "for", "timeout", "not"})


def plan_to_text(plan: Plan) -> str:
    """The plan's text form; parse_plan_text reads it back to an equal plan."""
    lines: list[str] = []
    _write(plan.steps, 0, lines)
    return "".join(line + "\n" for line in lines)


def check_written_form(plan: Plan) -> list[PlanError]:
    """The plan written out as text must itself be within the text's limits, so every plan can be shown and read."""
    text = plan_to_text(plan)
    size, lines = len(text.encode("utf-8", "surrogatepass")), text.count("\n")
    if size > MAX_TEXT_BYTES or lines > MAX_LINES:
        return [place_error(0, 0, "steps", gettext(
            "Written out one command a line this plan has %(lines)s lines and %(size)s bytes; a plan has at most "
            "%(max_lines)s lines and %(max_size)s bytes.", lines=grouped(lines), size=grouped(size),
            max_lines=MAX_LINES, max_size=grouped(MAX_TEXT_BYTES)))]
    return []


def number_text(value: float | int) -> str:
    """The shortest numeral that reads back to value exactly."""
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(float(value))


def _angle_text(radians: float) -> str:
    """An angle in degrees when a short numeral of degrees reads back to exactly these radians."""
    degrees = math.degrees(radians)
    for digits in range(7):
        candidate = number_text(round(degrees, digits))
        if math.radians(float(candidate)) == radians:
            return f"{candidate}deg"
    return number_text(radians)


def _value_text(name: str, value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and name.endswith("_rad"):
        return _angle_text(value)
    if isinstance(value, int | float):
        return number_text(value)
    text = str(value)
    if text and text[0] in _WORD_START and set(text) <= _WORD and text not in _KEYWORDS:
        return text
    return quoted(text)


def quoted(text: str) -> str:
    """text in double quotes, with " and \\ escaped."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _seconds(value: float) -> str:
    return f"{number_text(value)}s"


def _skill_line(step: SkillStep) -> str:
    names = [name for name, _ in step.parameters]
    alias_name = ALIAS_OF_SKILL.get(step.skill)
    words: list[str]
    if alias_name is not None:
        alias = ALIASES[alias_name]
        leading = 0
        while leading < len(alias.positional) and leading < len(names) and names[leading] == alias.positional[leading]:
            leading += 1
        if leading >= alias.required:
            words = [alias_name, *(_value_text(n, v) for n, v in step.parameters[:leading])]
            words += [f"{n}={_value_text(n, v)}" for n, v in step.parameters[leading:]]
        else:
            alias_name = None
    if alias_name is None:
        words = [step.skill, *(f"{n}={_value_text(n, v)}" for n, v in step.parameters)]
    if step.duration_s is not None:
        words += ["for", _seconds(step.duration_s)]
    return " ".join(words)


def _condition_text(condition: Condition) -> str:
    words = ["not"] if condition.negate else []
    words.append(condition.kind)
    if condition.value is not None:
        words.append(number_text(condition.value))
    return " ".join(words)


def _write(steps: tuple[Step, ...], depth: int, lines: list[str]) -> None:
    indent = INDENT * depth
    for step in steps:
        if isinstance(step, SkillStep):
            lines.append(indent + _skill_line(step))
        elif isinstance(step, DriveStep):
            lines.append(f"{indent}drive {number_text(step.linear_mps)} {number_text(step.angular_radps)} "
                         f"for {_seconds(step.duration_s)}")
        elif isinstance(step, WaitStep):
            if step.condition is None:
                lines.append(f"{indent}wait {_seconds(step.duration_s or 0.0)}")
            else:
                timeout = f" timeout {_seconds(step.duration_s)}" if step.duration_s is not None else ""
                lines.append(f"{indent}wait_until {_condition_text(step.condition)}{timeout}")
        elif isinstance(step, RepeatStep):
            lines.append(f"{indent}repeat {step.count} {{")
            _write(step.body, depth + 1, lines)
            lines.append(indent + "}")
        elif isinstance(step, IfStep):
            lines.append(f"{indent}if {_condition_text(step.condition)} {{")
            _write(step.then, depth + 1, lines)
            if step.otherwise:
                lines.append(indent + "} else {")
                _write(step.otherwise, depth + 1, lines)
            lines.append(indent + "}")
        elif isinstance(step, SetStep):
            value = _seconds(step.value) if step.setting == "watchdog" else number_text(step.value)
            lines.append(f"{indent}set {step.setting} {value}")
        elif isinstance(step, SayStep):
            lines.append(f"{indent}say {quoted(step.text)}")
        elif isinstance(step, OnStep):
            value = "" if step.value is None else f" {number_text(step.value)}"
            lines.append(f"{indent}on {step.event}{value} {{")
            _write(step.body, depth + 1, lines)
            lines.append(indent + "}")
