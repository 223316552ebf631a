"""The plan's JSON form (the API's and the export file's): any JSON value checked into a Plan, every problem named
by its JSON path ("steps[2].body[0].count") and by the line and column the step carries, and a Plan written back."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.plans import checks
from middleware.plans.checks import StepProblem, place_error, shown
from middleware.plans.steps import (
    FORMAT,
    MAX_DEPTH,
    MAX_STEPS,
    Condition,
    DriveStep,
    IfStep,
    OnStep,
    Plan,
    PlanError,
    PlanInvalid,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    Step,
    WaitStep,
)
from middleware.plans.text_writer import check_written_form
from middleware.teaching.command_form import SkillSchemas

MAX_POSITION = 1_000_000
_COMMON = ("line", "column", "kind")
KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {  # kind -> (required keys, optional keys)
    "skill": (("skill",), ("parameters", "duration_s")),
    "drive": (("linear_mps", "angular_radps", "duration_s"), ()),
    "wait": ((), ("condition", "duration_s")),
    "repeat": (("count", "body"), ()),
    "if": (("condition", "then"), ("else",)),
    "set": (("setting", "value"), ()),
    "say": (("text",), ()),
    "on": (("event", "body"), ("value",)),
}


def plan_to_json(plan: Plan) -> dict[str, object]:
    """The canonical JSON form: {"format": "telelab-plan/1", "steps": [...]}."""
    return {"format": FORMAT, "steps": [_step_json(step) for step in plan.steps]}


def _condition_json(condition: Condition | None) -> dict[str, object] | None:
    if condition is None:
        return None
    return {"kind": condition.kind, "value": condition.value, "negate": condition.negate}


def _step_json(step: Step) -> dict[str, object]:
    head: dict[str, object] = {"line": step.line, "column": step.column}
    if isinstance(step, SkillStep):
        return {**head, "kind": "skill", "skill": step.skill, "parameters": dict(step.parameters),
                "duration_s": step.duration_s}
    if isinstance(step, DriveStep):
        return {**head, "kind": "drive", "linear_mps": step.linear_mps, "angular_radps": step.angular_radps,
                "duration_s": step.duration_s}
    if isinstance(step, WaitStep):
        return {**head, "kind": "wait", "condition": _condition_json(step.condition), "duration_s": step.duration_s}
    if isinstance(step, RepeatStep):
        return {**head, "kind": "repeat", "count": step.count, "body": [_step_json(s) for s in step.body]}
    if isinstance(step, IfStep):
        return {**head, "kind": "if", "condition": _condition_json(step.condition),
                "then": [_step_json(s) for s in step.then], "else": [_step_json(s) for s in step.otherwise]}
    if isinstance(step, SetStep):
        return {**head, "kind": "set", "setting": step.setting, "value": step.value}
    if isinstance(step, OnStep):
        return {**head, "kind": "on", "event": step.event, "value": step.value,
                "body": [_step_json(s) for s in step.body]}
    return {**head, "kind": "say", "text": step.text}


def plan_from_json(doc: object, skills: SkillSchemas) -> Plan:
    """The plan a JSON value describes, or PlanInvalid with every problem found."""
    reader = _Reader(skills)
    steps: list[Step] = []
    if not isinstance(doc, dict):
        reader.report(0, 0, "plan", gettext('A plan is a JSON object: {"format": "telelab-plan/1", "steps": [...]}.'))
    else:
        reader.unknown_keys(doc, ("format", "steps"), "", 0, 0)
        if "format" in doc and doc["format"] != FORMAT:
            reader.report(0, 0, "format", gettext("format must be %(format)s; got %(value)s.", format=repr(FORMAT),
                                                  value=shown(doc["format"])))
        if "steps" not in doc:
            reader.report(0, 0, "steps", gettext("A plan needs its steps: a list of commands."))
        else:
            try:
                steps = reader.block(doc["steps"], "steps", 0)
            except checks.TooManyErrors:
                raise PlanInvalid(reader.errors) from None
    if not reader.errors:
        reader.errors += checks.handler_errors(steps)
    if not reader.errors:
        reader.errors += checks.plan_totals(steps)
    plan = Plan(tuple(steps))
    if not reader.errors:
        reader.errors += check_written_form(plan)
    if reader.errors:
        raise PlanInvalid(reader.errors)
    return plan


def _safe_key(key: object) -> str:
    text = str(key)
    if text.isascii() and text.isidentifier() and len(text) <= 40:
        return text
    return repr(text[:40])


class _Reader:
    """Reads steps from JSON, collecting problems; a refused step leaves a gap and reading goes on."""

    def __init__(self, skills: SkillSchemas) -> None:
        self.skills = skills
        self.errors: list[PlanError] = []
        self.count = 0

    def report(self, line: int, column: int, field: str, message: str) -> None:
        """Adds a problem; at MAX_ERRORS reading stops (TooManyErrors)."""
        checks.add_error(self.errors, place_error(line, column, field, message))

    def unknown_keys(self, value: Mapping[object, object], allowed: tuple[str, ...], path: str, line: int,
                     column: int) -> bool:
        """Reports the first key not allowed; True when there was one."""
        extra = [key for key in value if key not in allowed]
        if extra:
            key = _safe_key(extra[0])
            where = f"{path}.{key}" if path else key
            self.report(line, column, where, gettext("unknown key %(key)s (allowed: %(allowed)s).", key=key,
                                                     allowed=", ".join(allowed)))
        return bool(extra)

    def block(self, value: object, path: str, depth: int) -> list[Step]:
        """The steps of a list."""
        if not isinstance(value, list):
            self.report(0, 0, path, gettext("%(field)s must be a list of steps; got %(value)s.", field=path,
                                            value=shown(value)))
            return []
        steps: list[Step] = []
        failed = False
        for index, item in enumerate(value):
            self.count += 1
            if self.count > MAX_STEPS:
                self.report(0, 0, f"{path}[{index}]", gettext("A plan has at most %(max)s steps.", max=MAX_STEPS))
                return steps
            step = self.step(item, f"{path}[{index}]", depth)
            if step is None:
                failed = True
            else:
                steps.append(step)
        return [] if failed else steps

    def step(self, value: object, path: str, depth: int) -> Step | None:
        """One step, or None when it is refused (reported)."""
        if not isinstance(value, dict):
            self.report(0, 0, path, gettext("A step is a JSON object with a kind; got %(value)s.", value=shown(value)))
            return None
        line, column = self._position(value, path)
        kind = value.get("kind")
        if not isinstance(kind, str) or kind not in KEYS:
            self.report(line, column, f"{path}.kind", gettext("%(field)s must be one of %(choices)s; got %(value)s.",
                                                              field="kind", choices=", ".join(KEYS),
                                                              value=shown(kind)))
            return None
        required, optional = KEYS[kind]
        if self.unknown_keys(value, (*_COMMON, *required, *optional), path, line, column):
            return None
        missing = [key for key in required if key not in value]
        if missing:
            needs = (gettext("an if step needs %(missing)s.", missing=", ".join(missing)) if kind == "if" else
                     gettext("a %(kind)s step needs %(missing)s.", kind=kind, missing=", ".join(missing)))
            self.report(line, column, f"{path}.{missing[0]}", needs)
            return None
        readers: Mapping[str, Callable[[dict[str, object], str, int], Step | None]] = {
            "skill": self._skill, "drive": self._drive, "wait": self._wait, "repeat": self._repeat, "if": self._if,
            "set": self._set, "say": self._say, "on": self._on,
        }
        try:
            step = readers[kind](value, path, depth)
        except StepProblem as problem:
            field = f"{path}.{problem.field}" if problem.field else path
            self.report(line, column, field, problem.message)
            return None
        if step is None:
            return None
        return _placed(step, line, column)

    def _position(self, value: Mapping[str, object], path: str) -> tuple[int, int]:
        place = []
        for key in ("line", "column"):
            number = value.get(key, 0)
            if isinstance(number, bool) or not isinstance(number, int) or not 0 <= number <= MAX_POSITION:
                self.report(0, 0, f"{path}.{key}", gettext("%(field)s must be a whole number from 0 to %(max)s; got "
                                                           "%(value)s.", field=key, max=checks.grouped(MAX_POSITION),
                                                           value=shown(number)))
                number = 0
            place.append(number)
        return place[0], place[1]

    def _skill(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        skill = value["skill"]
        if not isinstance(skill, str):
            raise StepProblem("skill", gettext("skill must be a skill's name; got %(value)s.", value=shown(skill)))
        schema = checks.skill_schema(skill, self.skills)
        parameters = value.get("parameters", {})
        if parameters is None:
            parameters = {}
        if not isinstance(parameters, dict) or len(parameters) > checks.MAX_PARAMETERS:
            raise StepProblem("parameters", gettext("parameters must be an object of at most %(max)s values; got "
                                                    "%(value)s.", max=checks.MAX_PARAMETERS, value=shown(parameters)))
        checked: list[tuple[str, object]] = []
        for name, item in parameters.items():
            checked.append((name, checks.skill_parameter(skill, schema, name, item)))
        duration = value.get("duration_s")
        return SkillStep(skill, tuple(checked), None if duration is None else checks.duration(duration))

    def _drive(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        return DriveStep(checks.drive_value("linear_mps", value["linear_mps"], self.skills),
                         checks.drive_value("angular_radps", value["angular_radps"], self.skills),
                         checks.duration(value["duration_s"]))

    def _condition(self, value: object, field: str) -> Condition:
        if not isinstance(value, dict):
            raise StepProblem(field, gettext('%(field)s must be an object such as {"kind": "obstacle_within", '
                                             '"value": 0.5}; got %(value)s.', field=field, value=shown(value)))
        extra = [key for key in value if key not in ("kind", "value", "negate")]
        if extra:
            raise StepProblem(f"{field}.{_safe_key(extra[0])}", gettext("unknown key %(key)s (allowed: %(allowed)s).",
                                                                        key=_safe_key(extra[0]),
                                                                        allowed="kind, value, negate"))
        kind, negate = value.get("kind"), value.get("negate", False)
        if not isinstance(negate, bool):
            raise StepProblem(f"{field}.negate", gettext("negate must be true or false; got %(value)s.",
                                                         value=shown(negate)))
        if not isinstance(kind, str):
            raise StepProblem(f"{field}.kind", gettext("%(field)s must be one of %(choices)s; got %(value)s.",
                                                       field="kind", choices=", ".join(checks.CONDITION_KINDS),
                                                       value=shown(kind)))
        try:
            return checks.condition(kind, value.get("value"), negate)
        except StepProblem as problem:
            raise StepProblem(f"{field}.{problem.field}", problem.message) from None

    def _wait(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        condition = value.get("condition")
        duration = value.get("duration_s")
        if condition is None and duration is None:
            raise StepProblem("duration_s", gettext("a wait needs a duration_s, a condition, or both."))
        return WaitStep(None if condition is None else self._condition(condition, "condition"),
                        None if duration is None else checks.duration(duration))

    def _nested(self, value: object, path: str, depth: int, line: int) -> list[Step] | None:
        if depth + 1 > MAX_DEPTH:
            self.report(line, 0, path, gettext("blocks nest at most %(max)s deep; this one would be %(depth)s deep.",
                                               max=MAX_DEPTH, depth=depth + 1))
            return None
        before = len(self.errors)
        steps = self.block(value, path, depth + 1)
        return None if len(self.errors) > before else steps

    def _repeat(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        try:
            count: int | None = checks.repeat_count(value["count"])
        except StepProblem as problem:
            self.report(_line(value), _column(value), f"{path}.count", problem.message)
            count = None
        body = self._nested(value["body"], f"{path}.body", depth, _line(value))
        if count is None or body is None:
            return None
        if not body:
            raise StepProblem("body", gettext("this repeat has nothing in its body."))
        return RepeatStep(count, tuple(body))

    def _if(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        try:
            condition: Condition | None = self._condition(value["condition"], "condition")
        except StepProblem as problem:
            self.report(_line(value), _column(value), f"{path}.{problem.field}", problem.message)
            condition = None
        then = self._nested(value["then"], f"{path}.then", depth, _line(value))
        otherwise = self._nested(value.get("else", []), f"{path}.else", depth, _line(value))
        if condition is None or then is None or otherwise is None:
            return None
        return IfStep(condition, tuple(then), tuple(otherwise))

    def _set(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        setting = value["setting"]
        if not isinstance(setting, str):
            raise StepProblem("setting", gettext("%(field)s must be one of %(choices)s; got %(value)s.",
                                                 field="setting", choices=", ".join(checks.SETTINGS),
                                                 value=shown(setting)))
        return SetStep(setting, checks.setting_value(setting, value["value"], self.skills))

    def _on(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        event = value["event"]
        try:
            if not isinstance(event, str):
                raise StepProblem("event", gettext("%(field)s must be one of %(choices)s; got %(value)s.",
                                                   field="event", choices=", ".join(checks.EVENTS), value=shown(event)))
            threshold: float | None = checks.event_value(event, value.get("value"))
        except StepProblem as problem:
            self.report(_line(value), _column(value), f"{path}.{problem.field}", problem.message)
            return None
        body = self._nested(value["body"], f"{path}.body", depth, _line(value))
        if body is None:
            return None
        return OnStep(event, threshold, tuple(body))

    def _say(self, value: dict[str, object], path: str, depth: int) -> Step | None:
        return SayStep(checks.say_text(value["text"]))


def _line(value: Mapping[str, object]) -> int:
    line = value.get("line", 0)
    return line if isinstance(line, int) and not isinstance(line, bool) and 0 <= line <= MAX_POSITION else 0


def _column(value: Mapping[str, object]) -> int:
    column = value.get("column", 0)
    return column if isinstance(column, int) and not isinstance(column, bool) and 0 <= column <= MAX_POSITION else 0


def _placed(step: Step, line: int, column: int) -> Step:
    return replace(step, line=line, column=column)
