"""The plan's text form read by a recursive-descent parser over middleware.plans.tokens: one command a line,
blocks in braces, every problem reported with its line and column, as many as one pass finds."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from middleware.plans import checks
from middleware.plans.aliases import ALIASES, Alias, parameter_for_key
from middleware.plans.checks import StepProblem, place_error
from middleware.plans.steps import (
    MAX_DEPTH,
    MAX_LINES,
    MAX_TEXT_BYTES,
    Condition,
    DriveStep,
    IfStep,
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
from middleware.plans.tokens import Kind, Token, Tokenizer
from middleware.teaching.command_form import SkillSchemas

COMMANDS = ("drive", "wait", "wait_until", "repeat", "if", "set", "say", *ALIASES)
_LINE_ENDS = (Kind.NEWLINE, Kind.END, Kind.CLOSE, Kind.OPEN)


class _Reported(Exception):
    """The command is refused and its problem already reported."""


@dataclass
class _Arguments:
    """A command's words after its name: values by position, key=value pairs, and clauses such as for 20s."""

    positional: list[Token] = field(default_factory=list)
    keywords: list[tuple[Token, Token]] = field(default_factory=list)
    clauses: dict[str, tuple[Token, Token]] = field(default_factory=dict)


def parse_plan_text(text: str, skills: SkillSchemas) -> Plan:
    """The plan a text describes, or PlanInvalid with every problem found (each with its line and column)."""
    if not isinstance(text, str):
        raise PlanInvalid([place_error(0, 0, "text", "The plan's text must be a string.")])
    size = len(text) if len(text) > MAX_TEXT_BYTES else len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_TEXT_BYTES:
        raise PlanInvalid([place_error(0, 0, "text", f"The plan is {size:,} bytes long or more; a plan has at "
                                                     f"most {MAX_TEXT_BYTES:,} bytes (UTF-8).")])
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines[-1] == "":
        lines.pop()
    if len(lines) > MAX_LINES:
        raise PlanInvalid([place_error(0, 0, "text", f"The plan has {len(lines):,} lines; a plan has at most "
                                                     f"{MAX_LINES} lines.")])
    parser = _Parser(skills)
    try:
        parser.tokens = Tokenizer(parser.report).read(lines)
        steps = parser.block("steps", 0, None)
    except checks.TooManyErrors:
        raise PlanInvalid(parser.errors) from None
    if not parser.errors:
        parser.errors += checks.plan_totals(steps)
    plan = Plan(tuple(steps))
    if not parser.errors:
        parser.errors += check_written_form(plan)
    if parser.errors:
        raise PlanInvalid(parser.errors)
    return plan


class _Parser:
    """Commands and blocks from tokens; a refused command leaves a gap and the parser goes on with the next."""

    def __init__(self, skills: SkillSchemas) -> None:
        self.skills = skills
        self.tokens: list[Token] = []
        self.position = 0
        self.errors: list[PlanError] = []

    def report(self, line: int, column: int, message: str, field: str = "text") -> None:
        """Adds a problem; at MAX_ERRORS reading stops (TooManyErrors)."""
        checks.add_error(self.errors, place_error(line, column, field, message))

    def _at(self, token: Token, field: str, message: str) -> _Reported:
        self.report(token.line, token.column, message, field)
        return _Reported()

    def peek(self) -> Token:
        return self.tokens[self.position]

    def advance(self) -> Token:
        token = self.tokens[self.position]
        if token.kind is not Kind.END:
            self.position += 1
        return token

    def block(self, path: str, depth: int, opener: Token | None) -> list[Step]:
        """The commands up to the } closing opener (or the end of the plan when opener is None)."""
        steps: list[Step] = []
        written = 0  # commands met, refused ones included, so paths match the lines
        while True:
            token = self.peek()
            if token.kind is Kind.NEWLINE:
                self.advance()
            elif token.kind is Kind.END:
                if opener is not None:
                    self.report(opener.line, opener.column, "this { is never closed; end its block with }.", path)
                return steps
            elif token.kind is Kind.CLOSE:
                self.advance()
                if opener is not None:
                    return steps
                self.report(token.line, token.column, "this } closes no block; remove it.", path)
            else:
                step = self.statement(f"{path}[{written}]", depth)
                written += 1
                if step is not None:
                    steps.append(step)

    def statement(self, path: str, depth: int) -> Step | None:
        """One command: a block command (repeat, if) or a simple one that ends with its line."""
        head = self.advance()
        if head.kind is Kind.WORD and head.text == "repeat":
            return self._repeat(head, path, depth)
        if head.kind is Kind.WORD and head.text == "if":
            return self._if(head, path, depth)
        if head.kind is Kind.OPEN:
            self.report(head.line, head.column, "a { block } belongs after repeat, if or else.", path)
            self._skip_block(head, path)
            return None
        if head.kind is Kind.WORD and head.text == "else":
            self.report(head.line, head.column, "else must follow the } of an if: if ... { } else { }.", path)
            self._line_tokens()
            if self.peek().kind is Kind.OPEN:
                self._skip_block(self.advance(), path)
            return None
        arguments = self._line_tokens()
        if self.peek().kind is Kind.OPEN:
            opener = self.advance()
            self.report(opener.line, opener.column, "only repeat, if and else take a { block }.", path)
            self._skip_block(opener, path)
            return None
        try:
            if head.kind is Kind.BAD or any(t.kind is Kind.BAD for t in arguments):
                raise _Reported()
            if head.kind is not Kind.WORD:
                raise self._at(head, path, f"a command starts with its name, such as go_to or say; got "
                                           f"{head.written[:40]!r}.")
            return self._simple(head, arguments, path)
        except _Reported:
            return None

    def _line_tokens(self) -> list[Token]:
        tokens = []
        while self.peek().kind not in _LINE_ENDS:
            tokens.append(self.advance())
        return tokens

    def _skip_block(self, opener: Token, path: str) -> None:
        depth = 1
        while depth:
            token = self.advance()
            if token.kind is Kind.END:
                self.report(opener.line, opener.column, "this { is never closed; end its block with }.", path)
                return
            depth += {Kind.OPEN: 1, Kind.CLOSE: -1}.get(token.kind, 0)

    def _opening_brace(self, head: Token, path: str) -> Token | None:
        """The { of a block, on the same line or the next; None (reported) when there is none."""
        start = self.position
        while self.peek().kind is Kind.NEWLINE:
            self.advance()
        if self.peek().kind is Kind.OPEN:
            return self.advance()
        self.position = start
        self.report(head.line, head.column, f"{head.text} needs a block: {head.text} ... {{ commands }}.", path)
        return None

    def _nested_block(self, head: Token, path: str, depth: int) -> list[Step] | None:
        opener = self._opening_brace(head, path)
        if opener is None:
            return None
        if depth + 1 > MAX_DEPTH:
            self.report(opener.line, opener.column, f"blocks nest at most {MAX_DEPTH} deep; this one would be "
                                                    f"{depth + 1} deep.", path)
            self._skip_block(opener, path)
            return None
        body = self.block(path, depth + 1, opener)
        self._end_of_block_line(path)
        return body

    def _end_of_block_line(self, path: str) -> None:
        token = self.peek()
        if token.kind in (Kind.NEWLINE, Kind.END, Kind.CLOSE) or (token.kind is Kind.WORD and token.text == "else"):
            return
        self.report(token.line, token.column, "after a block's }, start the next command on a new line.", path)
        self._line_tokens()

    def _repeat(self, head: Token, path: str, depth: int) -> Step | None:
        header = self._line_tokens()
        count: int | None = None
        try:
            if any(t.kind is Kind.BAD for t in header):
                raise _Reported()
            if len(header) != 1:
                raise self._at(header[1] if len(header) > 1 else head, f"{path}.count",
                               "repeat takes one count and a block: repeat 3 { ... }.")
            count = checks.repeat_count(self._number(header[0], "", "count", f"{path}.count"), header[0].written)
        except StepProblem as problem:
            self.report(header[0].line, header[0].column, problem.message, f"{path}.count")
        except _Reported:
            pass
        before = len(self.errors)
        body = self._nested_block(head, f"{path}.body", depth)
        if count is None or body is None or len(self.errors) > before:
            return None
        if not body:
            self.report(head.line, head.column, "this repeat has nothing in its block.", f"{path}.body")
            return None
        return RepeatStep(count, tuple(body), head.line, head.column)

    def _if(self, head: Token, path: str, depth: int) -> Step | None:
        header = self._line_tokens()
        try:
            condition = self._condition(head, header, f"{path}.condition")
        except _Reported:
            condition = None
        then = self._nested_block(head, f"{path}.then", depth)
        otherwise: list[Step] | None = []
        start = self.position
        while self.peek().kind is Kind.NEWLINE:
            self.advance()
        if self.peek().kind is Kind.WORD and self.peek().text == "else":
            otherwise_head = self.advance()
            stray = self._line_tokens()
            if stray:
                self.report(stray[0].line, stray[0].column, "else takes no condition: else { ... }.", f"{path}.else")
            otherwise = self._nested_block(otherwise_head, f"{path}.else", depth)
        else:
            self.position = start
        if condition is None or then is None or otherwise is None:
            return None
        return IfStep(condition, tuple(then), tuple(otherwise), head.line, head.column)

    def _simple(self, head: Token, tokens: list[Token], path: str) -> Step | None:
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
        hint = f" (did you mean {joined}, with _?)" if joined in known else checks.did_you_mean(name, known)
        raise self._at(head, f"{path}.skill", f"{name[:40]!r} is not a command or a skill of this robot"
                                              f"{hint}; commands: {', '.join(COMMANDS)}; "
                                              f"skills: {', '.join(sorted(self.skills)) or 'none'}.")

    def _units_apart(self, tokens: list[Token], path: str) -> None:
        """Refuses 90 deg (a unit standing apart from its number) with the way to write it."""
        for previous, token in zip(tokens, tokens[1:], strict=False):
            if (token.kind is Kind.WORD and token.text in checks.UNITS and previous.kind is Kind.NUMBER
                    and not previous.unit):
                raise self._at(token, path, f"write a unit against its number, without a space: "
                                            f"{previous.written}{token.text}.")

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
                    raise self._at(following, path, f"{token.text}= needs a value, as in {token.text}=0.3.")
                arguments.keywords.append((token, value))
                index += 3
            elif token.kind is Kind.WORD and token.text in clause_words:
                if following is None or following.kind is Kind.EQUALS:
                    raise self._at(token, path, f"{token.text} needs a time, as in {token.text} 20s.")
                if token.text in arguments.clauses:
                    raise self._at(token, path, f"{token.text} is given twice.")
                arguments.clauses[token.text] = (token, following)
                index += 2
            elif token.kind is Kind.EQUALS:
                raise self._at(token, path, "= stands between a name and its value, as in speed=0.3.")
            else:
                if arguments.keywords or arguments.clauses:
                    raise self._at(token, path, "values without a name come first, before name=value and for.")
                arguments.positional.append(token)
                index += 1
        return arguments

    def _number(self, token: Token, unit: str, name: str, field: str) -> object:
        """A token's value for a parameter measured in unit: a number converted to it, true/false, or a word."""
        if token.kind is Kind.NUMBER:
            try:
                return checks.convert_unit(token.number, token.unit, unit, name, token.written)
            except StepProblem as problem:
                raise self._at(token, problem.field or field, problem.message) from None
        if token.kind is Kind.WORD and token.text in ("true", "false"):
            return token.text == "true"
        return token.text

    def _duration(self, clause: tuple[Token, Token] | None, path: str) -> float | None:
        if clause is None:
            return None
        keyword, token = clause
        if token.kind is not Kind.NUMBER:
            raise self._at(token, f"{path}.duration_s", f"{keyword.text} needs a time, as in {keyword.text} 20s.")
        try:
            return checks.duration(self._number(token, "s", "a duration", f"{path}.duration_s"), written=token.written)
        except StepProblem as problem:
            raise self._at(token, f"{path}.duration_s", problem.message) from None

    def _skill(self, head: Token, arguments: _Arguments, path: str, skill: str, alias: Alias | None) -> Step:
        try:
            schema = checks.skill_schema(skill, self.skills)
        except StepProblem as problem:
            message = (f"{head.text} needs the skill {skill}, which this robot does not have." if alias
                       else problem.message)
            raise self._at(head, f"{path}.skill", message) from None
        names = alias.positional if alias else ()
        if len(arguments.positional) > len(names):
            extra = arguments.positional[len(names)]
            first = next(iter(schema), "name")
            message = (f"{head.text} takes at most {len(names)} value{'s' if len(names) > 1 else ''} without a name "
                       f"({', '.join(names)}), as in {alias.example}." if alias else
                       f"{skill} takes its parameters as name=value, as in {first}=...")
            raise self._at(extra, path, message)
        pairs = [(name, token, token) for name, token in zip(names, arguments.positional, strict=False)]
        pairs += [(parameter_for_key(key.text, schema, alias), key, value) for key, value in arguments.keywords]
        given = [name for name, _, _ in pairs]
        if alias and (missing := [n for n in names[:alias.required] if n not in given]):
            raise self._at(head, f"{path}.parameters.{missing[0]}",
                           f"{head.text} needs {', '.join(missing)}, as in {alias.example}.")
        parameters: list[tuple[str, object]] = []
        failed = False
        for name, key, token in pairs:
            field = f"{path}.parameters.{name}"
            try:
                if name in dict(parameters) or name not in schema:
                    token = key
                if name in dict(parameters):
                    raise StepProblem(f"parameters.{name}", f"{name} is given twice.")
                unit = str(schema[name].get("unit") or "") if name in schema else ""
                value = self._number(token, unit, name, field)
                parameters.append((name, checks.skill_parameter(skill, schema, name, value, token.written)))
            except StepProblem as problem:
                self.report(token.line, token.column, problem.message, f"{path}.{problem.field}")
                failed = True
            except _Reported:
                failed = True
        duration = self._duration(arguments.clauses.get("for"), path)
        if failed:
            raise _Reported()
        return SkillStep(skill, tuple(parameters), duration, head.line, head.column)

    def _drive(self, head: Token, tokens: list[Token], path: str) -> Step:
        arguments = self._arguments(tokens, ("for",), path)
        if not 1 <= len(arguments.positional) <= 2 or arguments.keywords or "for" not in arguments.clauses:
            raise self._at(head, path, "drive takes a speed, a turn rate and a time: drive 0.2 0 for 2s "
                                       "(m/s, rad/s).")
        velocities = []
        measures = (("linear_mps", "m/s"), ("angular_radps", "rad/s"))
        for (name, unit), token in zip(measures, arguments.positional, strict=False):
            try:
                value = self._number(token, unit, name, f"{path}.{name}")
                velocities.append(checks.drive_value(name, value, self.skills, token.written))
            except StepProblem as problem:
                raise self._at(token, f"{path}.{name}", problem.message) from None
        linear, angular = velocities[0], velocities[1] if len(velocities) > 1 else 0.0
        duration = self._duration(arguments.clauses["for"], path)
        assert duration is not None
        return DriveStep(linear, angular, duration, head.line, head.column)

    def _wait(self, head: Token, tokens: list[Token], path: str) -> Step:
        self._units_apart(tokens, path)
        if len(tokens) != 1:
            raise self._at(tokens[1] if len(tokens) > 1 else head, path,
                           "wait takes one time, as in wait 2s (wait_until waits for a condition).")
        duration = self._duration((head, tokens[0]), path)
        return WaitStep(None, duration, head.line, head.column)

    def _wait_until(self, head: Token, tokens: list[Token], path: str) -> Step:
        arguments = self._arguments(tokens, ("timeout",), path)
        if arguments.keywords:
            raise self._at(arguments.keywords[0][0], path, "wait_until takes a condition and maybe a timeout: "
                                                           "wait_until not obstacle_within 0.5 timeout 10s.")
        condition = self._condition(head, arguments.positional, f"{path}.condition")
        duration = self._duration(arguments.clauses.get("timeout"), path)
        return WaitStep(condition, duration, head.line, head.column)

    def _condition(self, head: Token, tokens: list[Token], path: str) -> Condition:
        if any(t.kind is Kind.BAD for t in tokens):
            raise _Reported()
        self._units_apart(tokens, path)
        negate = bool(tokens) and tokens[0].kind is Kind.WORD and tokens[0].text == "not"
        tokens = tokens[1:] if negate else tokens
        if not tokens:
            raise self._at(head, f"{path}.kind", f"{head.text} needs a condition: obstacle_within 0.5, goal_reached "
                                                 "or battery_below 0.2 (not before one turns it round).")
        kind, values = tokens[0], tokens[1:]
        try:
            if kind.kind is not Kind.WORD:
                raise StepProblem("kind", f"a condition is a name such as obstacle_within; got {kind.written[:40]!r}.")
            schema = checks.condition_schema(kind.text)
        except StepProblem as problem:
            raise self._at(kind, f"{path}.kind", problem.message) from None
        if len(values) > 1:
            raise self._at(values[1], f"{path}.value", f"{kind.text} takes at most one value.")
        value = self._number(values[0], str((schema or {}).get("unit", "")), kind.text, f"{path}.value") if values \
            else None
        try:
            return checks.condition(kind.text, value, negate, values[0].written if values else None)
        except StepProblem as problem:
            raise self._at(values[0] if values else kind, f"{path}.{problem.field}", problem.message) from None

    def _set(self, head: Token, tokens: list[Token], path: str) -> Step:
        self._units_apart(tokens, path)
        if len(tokens) != 2 or tokens[0].kind is not Kind.WORD:
            raise self._at(head, path, "set takes a setting and a value: set max_speed 0.3, set max_turn_rate 1, "
                                       "set watchdog 0.5s.")
        setting, token = tokens
        try:
            schema = checks.setting_schema(setting.text, self.skills)
        except StepProblem as problem:
            raise self._at(setting, f"{path}.setting", problem.message) from None
        value = self._number(token, str(schema.get("unit", "")), setting.text, f"{path}.value")
        try:
            checked = checks.setting_value(setting.text, value, self.skills, token.written)
        except StepProblem as problem:
            raise self._at(token, f"{path}.value", problem.message) from None
        return SetStep(setting.text, checked, head.line, head.column)

    def _say(self, head: Token, tokens: list[Token], path: str) -> Step:
        if len(tokens) != 1 or tokens[0].kind is not Kind.TEXT:
            raise self._at(tokens[0] if tokens else head, f"{path}.text",
                           'say takes one text in double quotes: say "hello".')
        try:
            return SayStep(checks.say_text(tokens[0].text), head.line, head.column)
        except StepProblem as problem:
            raise self._at(tokens[0], f"{path}.text", problem.message) from None
