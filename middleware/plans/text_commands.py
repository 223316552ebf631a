"""The text form's simple commands (everything but repeat and if) read from their line's tokens: aliases and skills
with their parameters, drive, wait, wait_until, set, say, and the conditions of wait_until and if."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from flask_babel import gettext, ngettext  # type: ignore[import-untyped]

from middleware.plans import checks
from middleware.plans.aliases import ALIASES, Alias, parameter_for_key
from middleware.plans.checks import StepProblem
from middleware.plans.steps import Condition, DriveStep, SayStep, SetStep, SkillStep, Step, WaitStep
from middleware.plans.tokens import Kind, Token
from middleware.teaching.command_form import SkillSchemas

COMMANDS = ("drive", "wait", "wait_until", "repeat", "if", "on", "set", "say", *ALIASES)
Report = Callable[[int, int, str, str], None]  # line, column, message, field


class Reported(Exception):
    """The command is refused and its problem already reported."""


@dataclass
class _Arguments:
    """A command's words after its name: values by position, key=value pairs, and clauses such as for 20s."""

    positional: list[Token] = field(default_factory=list)
    keywords: list[tuple[Token, Token]] = field(default_factory=list)
    clauses: dict[str, tuple[Token, Token]] = field(default_factory=dict)


class CommandReader:
    """Reads one simple command, reporting each problem at its token."""

    def __init__(self, skills: SkillSchemas, report: Report) -> None:
        self.skills = skills
        self.report = report

    def at(self, token: Token, field: str, message: str) -> Reported:
        """Reports message at token; the Reported to raise."""
        self.report(token.line, token.column, message, field)
        return Reported()

    def simple(self, head: Token, tokens: list[Token], path: str) -> Step:
        """A command that ends with its line (anything but repeat and if), or Reported."""
        name = head.text
        if name in ALIASES:
            alias = ALIASES[name]
            return self._skill(head, self._arguments(tokens, ("for",), path), path, alias.skill, alias)
        handlers: Mapping[str, Callable[[Token, list[Token], str], Step]] = {
            "drive": self._drive, "wait": self._wait, "wait_until": self._wait_until, "set": self._set,
            "say": self._say,
        }
        if name in handlers:
            return handlers[name](head, tokens, path)
        if name in self.skills:
            return self._skill(head, self._arguments(tokens, ("for",), path), path, name, None)
        known = (*COMMANDS, *self.skills)
        joined = f"{name}_{tokens[0].text}" if tokens and tokens[0].kind is Kind.WORD else ""
        hint = (" " + gettext("(did you mean %(name)s, with _?)", name=joined) if joined in known
                else checks.did_you_mean(name, known))
        raise self.at(head, f"{path}.skill", gettext(
            "%(name)s is not a command or a skill of this robot%(hint)s; commands: %(commands)s; skills a plan can run "
            "(those that drive the wheels): %(skills)s.", name=repr(name[:40]), hint=hint,
            commands=", ".join(COMMANDS), skills=checks.listed(sorted(self.skills))))

    def _units_apart(self, tokens: list[Token], path: str) -> None:
        """Refuses 90 deg (a unit standing apart from its number) with the way to write it."""
        for previous, token in zip(tokens, tokens[1:], strict=False):
            if (token.kind is Kind.WORD and token.text in checks.UNITS and previous.kind is Kind.NUMBER
                    and not previous.unit):
                raise self.at(token, path, gettext("write a unit against its number, without a space: %(written)s.",
                                                   written=f"{previous.written}{token.text}"))

    def _arguments(self, tokens: list[Token], clause_words: tuple[str, ...], path: str) -> _Arguments:
        self._units_apart(tokens, path)
        arguments = _Arguments()
        index = 0
        while index < len(tokens):
            token = tokens[index]
            following = tokens[index + 1] if index + 1 < len(tokens) else None
            if token.kind is Kind.WORD and following is not None and following.kind is Kind.EQUALS:
                value = tokens[index + 2] if index + 2 < len(tokens) else None
                if value is None or value.kind is Kind.EQUALS:
                    raise self.at(following, path, gettext("%(name)s= needs a value, as in %(name)s=0.3.",
                                                           name=token.text))
                arguments.keywords.append((token, value))
                index += 3
            elif token.kind is Kind.WORD and token.text in clause_words:
                if following is None or following.kind is Kind.EQUALS:
                    raise self.at(token, path, gettext("%(word)s needs a time, as in %(word)s 20s.", word=token.text))
                if token.text in arguments.clauses:
                    raise self.at(token, path, gettext("%(name)s is given twice.", name=token.text))
                arguments.clauses[token.text] = (token, following)
                index += 2
            elif token.kind is Kind.EQUALS:
                raise self.at(token, path, gettext("= stands between a name and its value, as in speed=0.3."))
            else:
                if arguments.keywords or arguments.clauses:
                    raise self.at(token, path, gettext("values without a name come first, before name=value and "
                                                       "for."))
                arguments.positional.append(token)
                index += 1
        return arguments

    def number(self, token: Token, unit: str, name: str, field: str) -> object:
        """A token's value for a parameter measured in unit: a number converted to it, true/false, or a word."""
        if token.kind is Kind.NUMBER:
            try:
                return checks.convert_unit(token.number, token.unit, unit, name, token.written)
            except StepProblem as problem:
                raise self.at(token, problem.field or field, problem.message) from None
        if token.kind is Kind.WORD and token.text in ("true", "false"):
            return token.text == "true"
        return token.text

    def _duration(self, clause: tuple[Token, Token] | None, path: str) -> float | None:
        if clause is None:
            return None
        keyword, token = clause
        if token.kind is not Kind.NUMBER:
            raise self.at(token, f"{path}.duration_s", gettext("%(word)s needs a time, as in %(word)s 20s.",
                                                               word=keyword.text))
        try:
            return checks.duration(self.number(token, "s", gettext("a duration"), f"{path}.duration_s"),
                                   written=token.written)
        except StepProblem as problem:
            raise self.at(token, f"{path}.duration_s", problem.message) from None

    def _skill(self, head: Token, arguments: _Arguments, path: str, skill: str, alias: Alias | None) -> Step:
        try:
            schema = checks.skill_schema(skill, self.skills)
        except StepProblem as problem:
            message = (gettext("%(command)s needs the skill %(skill)s, which this robot does not have.",
                               command=head.text, skill=skill) if alias else problem.message)
            raise self.at(head, f"{path}.skill", message) from None
        names = alias.positional if alias else ()
        if len(arguments.positional) > len(names):
            extra = arguments.positional[len(names)]
            first = next(iter(schema), "name")
            message = (ngettext("%(command)s takes at most %(num)s value without a name (%(names)s), as in "
                                "%(example)s.", "%(command)s takes at most %(num)s values without a name (%(names)s), "
                                "as in %(example)s.", max(len(names), 1), command=head.text,
                                names=", ".join(names), example=alias.example) if alias else
                       gettext("%(skill)s takes its parameters as name=value, as in %(first)s=...", skill=skill,
                               first=first))
            raise self.at(extra, path, message)
        pairs = [(name, token, token) for name, token in zip(names, arguments.positional, strict=False)]
        pairs += [(parameter_for_key(key.text, schema, alias), key, value) for key, value in arguments.keywords]
        given = [name for name, _, _ in pairs]
        if alias and (missing := [n for n in names[:alias.required] if n not in given]):
            raise self.at(head, f"{path}.parameters.{missing[0]}",
                          gettext("%(command)s needs %(missing)s, as in %(example)s.", command=head.text,
                                  missing=", ".join(missing), example=alias.example))
        parameters: list[tuple[str, object]] = []
        seen: set[str] = set()
        failed = False
        for name, key, token in pairs:
            at = key if name in seen or name not in schema else token  # a name's problem at the name
            try:
                if name in seen:
                    raise StepProblem(f"parameters.{name}", gettext("%(name)s is given twice.", name=name))
                seen.add(name)
                unit = str(schema[name].get("unit") or "") if name in schema else ""
                value = self.number(at, unit, name, f"{path}.parameters.{name}")
                parameters.append((name, checks.skill_parameter(skill, schema, name, value, at.written)))
            except StepProblem as problem:
                self.report(at.line, at.column, problem.message, f"{path}.{problem.field}")
                failed = True
            except Reported:
                failed = True
        duration = self._duration(arguments.clauses.get("for"), path)
        if failed:
            raise Reported()
        return SkillStep(skill, tuple(parameters), duration, head.line, head.column)

    def _drive(self, head: Token, tokens: list[Token], path: str) -> Step:
        arguments = self._arguments(tokens, ("for",), path)
        if not 1 <= len(arguments.positional) <= 2 or arguments.keywords or "for" not in arguments.clauses:
            raise self.at(head, path, gettext("drive takes a speed, a turn rate and a time: drive 0.2 0 for 2s "
                                              "(m/s, rad/s)."))
        velocities = []
        measures = (("linear_mps", "m/s"), ("angular_radps", "rad/s"))
        for (name, unit), token in zip(measures, arguments.positional, strict=False):
            try:
                value = self.number(token, unit, name, f"{path}.{name}")
                velocities.append(checks.drive_value(name, value, self.skills, token.written))
            except StepProblem as problem:
                raise self.at(token, f"{path}.{name}", problem.message) from None
        linear, angular = velocities[0], velocities[1] if len(velocities) > 1 else 0.0
        duration = self._duration(arguments.clauses["for"], path)
        assert duration is not None
        return DriveStep(linear, angular, duration, head.line, head.column)

    def _wait(self, head: Token, tokens: list[Token], path: str) -> Step:
        self._units_apart(tokens, path)
        if len(tokens) != 1:
            raise self.at(tokens[1] if len(tokens) > 1 else head, path,
                          gettext("wait takes one time, as in wait 2s (wait_until waits for a condition)."))
        duration = self._duration((head, tokens[0]), path)
        return WaitStep(None, duration, head.line, head.column)

    def _wait_until(self, head: Token, tokens: list[Token], path: str) -> Step:
        arguments = self._arguments(tokens, ("timeout",), path)
        if arguments.keywords:
            raise self.at(arguments.keywords[0][0], path, gettext(
                "wait_until takes a condition and maybe a timeout: wait_until not obstacle_within 0.5 timeout 10s."))
        condition = self.condition(head, arguments.positional, f"{path}.condition")
        duration = self._duration(arguments.clauses.get("timeout"), path)
        return WaitStep(condition, duration, head.line, head.column)

    def condition(self, head: Token, tokens: list[Token], path: str) -> Condition:
        """A condition: [not] kind [value]."""
        if any(t.kind is Kind.BAD for t in tokens):
            raise Reported()
        self._units_apart(tokens, path)
        negate = bool(tokens) and tokens[0].kind is Kind.WORD and tokens[0].text == "not"
        tokens = tokens[1:] if negate else tokens
        if not tokens:
            raise self.at(head, f"{path}.kind", gettext(
                "%(command)s needs a condition: obstacle_within 0.5, goal_reached or battery_below 0.2 (not before one "
                "turns it round).", command=head.text))
        kind, values = tokens[0], tokens[1:]
        try:
            if kind.kind is not Kind.WORD:
                raise StepProblem("kind", gettext("a condition is a name such as obstacle_within; got %(written)s.",
                                                  written=repr(kind.written[:40])))
            schema = checks.condition_schema(kind.text)
        except StepProblem as problem:
            raise self.at(kind, f"{path}.kind", problem.message) from None
        if len(values) > 1:
            raise self.at(values[1], f"{path}.value", gettext("%(name)s takes at most one value.", name=kind.text))
        value = self.number(values[0], str((schema or {}).get("unit", "")), kind.text, f"{path}.value") if values \
            else None
        try:
            return checks.condition(kind.text, value, negate, values[0].written if values else None)
        except StepProblem as problem:
            raise self.at(values[0] if values else kind, f"{path}.{problem.field}", problem.message) from None

    def event(self, head: Token, tokens: list[Token], path: str) -> tuple[str, float | None]:
        """An on's header: an event and maybe its value (on obstacle_detected 0.3)."""
        if any(t.kind is Kind.BAD for t in tokens):
            raise Reported()
        self._units_apart(tokens, path)
        if not tokens:
            raise self.at(head, f"{path}.event", gettext("on needs an event: %(events)s, as in on obstacle_detected "
                                                         "{ ... }.", events=", ".join(checks.EVENTS)))
        name, values = tokens[0], tokens[1:]
        try:
            if name.kind is not Kind.WORD:
                raise StepProblem("event", gettext("an event is a name such as obstacle_detected; got %(written)s.",
                                                   written=repr(name.written[:40])))
            schema = checks.event_schema(name.text)
        except StepProblem as problem:
            raise self.at(name, f"{path}.event", problem.message) from None
        if len(values) > 1:
            raise self.at(values[1], f"{path}.value", gettext("%(name)s takes at most one value.", name=name.text))
        value = self.number(values[0], str((schema or {}).get("unit", "")), name.text, f"{path}.value") if values \
            else None
        try:
            return name.text, checks.event_value(name.text, value, values[0].written if values else None)
        except StepProblem as problem:
            raise self.at(values[0] if values else name, f"{path}.{problem.field}", problem.message) from None

    def _set(self, head: Token, tokens: list[Token], path: str) -> Step:
        self._units_apart(tokens, path)
        if len(tokens) != 2 or tokens[0].kind is not Kind.WORD:
            raise self.at(head, path, gettext("set takes a setting and a value: set max_speed 0.3, set max_turn_rate "
                                              "1, set watchdog 0.5s."))
        setting, token = tokens
        try:
            schema = checks.setting_schema(setting.text, self.skills)
        except StepProblem as problem:
            raise self.at(setting, f"{path}.setting", problem.message) from None
        value = self.number(token, str(schema.get("unit", "")), setting.text, f"{path}.value")
        try:
            checked = checks.setting_value(setting.text, value, self.skills, token.written)
        except StepProblem as problem:
            raise self.at(token, f"{path}.value", problem.message) from None
        return SetStep(setting.text, checked, head.line, head.column)

    def _say(self, head: Token, tokens: list[Token], path: str) -> Step:
        if len(tokens) != 1 or tokens[0].kind is not Kind.TEXT:
            raise self.at(tokens[0] if tokens else head, f"{path}.text",
                          gettext('say takes one text in double quotes: say "hello".'))
        try:
            return SayStep(checks.say_text(tokens[0].text), head.line, head.column)
        except StepProblem as problem:
            raise self.at(tokens[0], f"{path}.text", problem.message) from None
