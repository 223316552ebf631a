"""The plan's text form read by a recursive-descent parser over middleware.plans.tokens: one command a line,
blocks in braces, every problem reported with its line and column, as many as one pass finds."""

from __future__ import annotations

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.plans import checks
from middleware.plans.checks import StepProblem, place_error
from middleware.plans.steps import (
    MAX_DEPTH,
    MAX_LINES,
    MAX_TEXT_BYTES,
    IfStep,
    OnStep,
    Plan,
    PlanError,
    PlanInvalid,
    RepeatStep,
    Step,
)
from middleware.plans.text_commands import CommandReader, Reported
from middleware.plans.text_writer import check_written_form
from middleware.plans.tokens import Kind, Token, Tokenizer
from middleware.teaching.command_form import SkillSchemas

_LINE_ENDS = (Kind.NEWLINE, Kind.END, Kind.CLOSE, Kind.OPEN)


def parse_plan_text(text: str, skills: SkillSchemas) -> Plan:
    """The plan a text describes, or PlanInvalid with every problem found (each with its line and column)."""
    if not isinstance(text, str):
        raise PlanInvalid([place_error(0, 0, "text", gettext("The plan's text must be a string."))])
    size = len(text) if len(text) > MAX_TEXT_BYTES else len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_TEXT_BYTES:
        raise PlanInvalid([place_error(0, 0, "text", gettext(
            "The plan is %(size)s bytes long or more; a plan has at most %(max)s bytes (UTF-8).",
            size=checks.grouped(size), max=checks.grouped(MAX_TEXT_BYTES)))])
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines[-1] == "":
        lines.pop()
    if len(lines) > MAX_LINES:
        raise PlanInvalid([place_error(0, 0, "text", gettext("The plan has %(count)s lines; a plan has at most "
                                                             "%(max)s lines.", count=checks.grouped(len(lines)),
                                                             max=MAX_LINES))])
    parser = _Parser(skills)
    try:
        parser.tokens = Tokenizer(parser.report).read(lines)
        steps = parser.block("steps", 0, None)
    except checks.TooManyErrors:
        raise PlanInvalid(_in_reading_order(parser.errors)) from None
    if not parser.errors:
        parser.errors += checks.handler_errors(steps)
    if not parser.errors:
        parser.errors += checks.plan_totals(steps)
    plan = Plan(tuple(steps))
    if not parser.errors:
        parser.errors += check_written_form(plan)
    if parser.errors:
        raise PlanInvalid(_in_reading_order(parser.errors))
    return plan


def _in_reading_order(errors: list[PlanError]) -> list[PlanError]:
    """The tokenizer's errors and the parser's by line and column, as a reader meets them."""
    return sorted(errors, key=lambda error: (error.line, error.column))


class _Parser:
    """Commands and blocks from tokens; a refused command leaves a gap and the parser goes on with the next."""

    def __init__(self, skills: SkillSchemas) -> None:
        self.commands = CommandReader(skills, self.report)
        self.tokens: list[Token] = []
        self.position = 0
        self.errors: list[PlanError] = []

    def report(self, line: int, column: int, message: str, field: str = "text") -> None:
        """Adds a problem; at MAX_ERRORS reading stops (TooManyErrors)."""
        checks.add_error(self.errors, place_error(line, column, field, message))

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
                    self.report(opener.line, opener.column, gettext("this { is never closed; end its block with }."),
                                path)
                return steps
            elif token.kind is Kind.CLOSE:
                self.advance()
                if opener is not None:
                    return steps
                self.report(token.line, token.column, gettext("this } closes no block; remove it."), path)
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
        if head.kind is Kind.WORD and head.text == "on":
            return self._on(head, path, depth)
        if head.kind is Kind.OPEN:
            self.report(head.line, head.column, gettext("a { block } belongs after repeat, if, else or on."), path)
            self._skip_block(head, path)
            return None
        if head.kind is Kind.WORD and head.text == "else":
            self.report(head.line, head.column, gettext("else must follow the } of an if: if ... { } else { }."),
                        path)
            self._line_tokens()
            if self.peek().kind is Kind.OPEN:
                self._skip_block(self.advance(), path)
            return None
        arguments = self._line_tokens()
        if self.peek().kind is Kind.OPEN:
            opener = self.advance()
            self.report(opener.line, opener.column, gettext("only repeat, if, else and on take a { block }."),
                        path)
            self._skip_block(opener, path)
            return None
        try:
            if head.kind is Kind.BAD or any(t.kind is Kind.BAD for t in arguments):
                raise Reported()
            if head.kind is not Kind.WORD:
                raise self.commands.at(head, path, gettext("a command starts with its name, such as go_to or say; "
                                                           "got %(written)s.", written=repr(head.written[:40])))
            return self.commands.simple(head, arguments, path)
        except Reported:
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
                self.report(opener.line, opener.column, gettext("this { is never closed; end its block with }."),
                            path)
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
        self.report(head.line, head.column, gettext("%(command)s needs a block: %(command)s ... { commands }.",
                                                    command=head.text), path)
        return None

    def _nested_block(self, head: Token, path: str, depth: int) -> list[Step] | None:
        opener = self._opening_brace(head, path)
        if opener is None:
            return None
        if depth + 1 > MAX_DEPTH:
            self.report(opener.line, opener.column, gettext("blocks nest at most %(max)s deep; this one would be "
                                                            "%(depth)s deep.", max=MAX_DEPTH, depth=depth + 1), path)
            self._skip_block(opener, path)
            return None
        body = self.block(path, depth + 1, opener)
        self._end_of_block_line(path)
        return body

    def _end_of_block_line(self, path: str) -> None:
        token = self.peek()
        if token.kind in (Kind.NEWLINE, Kind.END, Kind.CLOSE) or (token.kind is Kind.WORD and token.text == "else"):
            return
        self.report(token.line, token.column, gettext("after a block's }, start the next command on a new line."),
                    path)
        self._line_tokens()

    def _repeat(self, head: Token, path: str, depth: int) -> Step | None:
        header = self._line_tokens()
        count: int | None = None
        try:
            if any(t.kind is Kind.BAD for t in header):
                raise Reported()
            if len(header) != 1:
                raise self.commands.at(header[1] if len(header) > 1 else head, f"{path}.count",
                                       gettext("repeat takes one count and a block: repeat 3 { ... }."))
            value = self.commands.number(header[0], "", "count", f"{path}.count")
            count = checks.repeat_count(value, header[0].written)
        except StepProblem as problem:
            self.report(header[0].line, header[0].column, problem.message, f"{path}.count")
        except Reported:
            pass
        before = len(self.errors)
        body = self._nested_block(head, f"{path}.body", depth)
        if count is None or body is None or len(self.errors) > before:
            return None
        if not body:
            self.report(head.line, head.column, gettext("this repeat has nothing in its block."), f"{path}.body")
            return None
        return RepeatStep(count, tuple(body), head.line, head.column)

    def _on(self, head: Token, path: str, depth: int) -> Step | None:
        header = self._line_tokens()
        try:
            event = self.commands.event(head, header, path)
        except Reported:
            event = None
        before = len(self.errors)
        body = self._nested_block(head, f"{path}.body", depth)
        if event is None or body is None or len(self.errors) > before:
            return None
        return OnStep(event[0], event[1], tuple(body), head.line, head.column)

    def _if(self, head: Token, path: str, depth: int) -> Step | None:
        header = self._line_tokens()
        try:
            condition = self.commands.condition(head, header, f"{path}.condition")
        except Reported:
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
                self.report(stray[0].line, stray[0].column, gettext("else takes no condition: else { ... }."),
                            f"{path}.else")
            otherwise = self._nested_block(otherwise_head, f"{path}.else", depth)
        else:
            self.position = start
        if condition is None or then is None or otherwise is None:
            return None
        return IfStep(condition, tuple(then), tuple(otherwise), head.line, head.column)
