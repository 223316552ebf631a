"""The plan text's tokens, read by hand one character at a time (no regular expressions, no eval): words,
numbers with an optional unit stuck to them (90deg, 0.5m/s), quoted texts, braces, '=' and line ends."""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.plans.checks import character_problem, text_character_problem

_LETTERS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ_")
_DIGITS = frozenset("0123456789")
_WORD_CHARACTERS = _LETTERS | _DIGITS
_UNIT_CHARACTERS = _LETTERS | frozenset("/%")
_ESCAPES = {'"': '"', "\\": "\\"}


class Kind(enum.Enum):
    """What a token is."""

    WORD = "word"
    NUMBER = "number"
    TEXT = "text"
    OPEN = "{"
    CLOSE = "}"
    EQUALS = "="
    NEWLINE = "end of line"
    END = "end of the plan"
    BAD = "bad"  # a token already reported by the tokenizer: the parser skips its command without a second error


@dataclass(frozen=True)
class Token:
    """One token and where it starts (1-based line and column, counting characters)."""

    kind: Kind
    written: str
    line: int
    column: int
    number: float = 0.0
    unit: str = ""
    text: str = ""  # a word's or a quoted text's value


ErrorSink = Callable[[int, int, str], None]  # line, column, message


class Tokenizer:
    """Splits a plan's text into tokens, collecting one error per bad token."""

    def __init__(self, report: ErrorSink) -> None:
        self._report = report
        self.tokens: list[Token] = []

    def read(self, lines: list[str]) -> list[Token]:
        """Every token of the lines, each line ending in NEWLINE, then END."""
        for number, line in enumerate(lines, start=1):
            self._read_line(line, number)
            self.tokens.append(Token(Kind.NEWLINE, "", number, len(line) + 1))
        self.tokens.append(Token(Kind.END, "", len(lines), 1))
        return self.tokens

    def _read_line(self, line: str, number: int) -> None:
        position = 0
        while position < len(line):
            character = line[position]
            if character in " \t":
                position += 1
            elif character == "#":
                self._check_comment(line, number, position)
                return
            elif character in "{}=":
                kind = {"{": Kind.OPEN, "}": Kind.CLOSE, "=": Kind.EQUALS}[character]
                self.tokens.append(Token(kind, character, number, position + 1))
                position += 1
            elif character == '"':
                position = self._read_text(line, number, position)
            elif character in _DIGITS or (character in "+-." and _starts_number(line, position)):
                position = self._read_number(line, number, position)
            elif character in _LETTERS:
                end = position
                while end < len(line) and line[end] in _WORD_CHARACTERS:
                    end += 1
                if end < len(line) and _is_other_letter(line[end]):
                    position = self._bad_word(line, number, position, end)
                    continue
                word = line[position:end]
                self.tokens.append(Token(Kind.WORD, word, number, position + 1, text=word))
                position = end
            else:
                position = self._bad_character(line, number, position)

    def _bad(self, number: int, position: int, written: str, message: str) -> None:
        self.tokens.append(Token(Kind.BAD, written, number, position + 1))
        self._report(number, position + 1, message)

    def _bad_character(self, line: str, number: int, position: int) -> int:
        character = line[position]
        if _is_other_letter(character):
            end = position
            while end < len(line) and (line[end] in _WORD_CHARACTERS or _is_other_letter(line[end])):
                end += 1
            return self._bad_word(line, number, position, end)
        problem = character_problem(character)
        if problem:
            self._bad(number, position, character, gettext("%(problem)s.", problem=problem))
        elif character == "'":
            self._bad(number, position, character, gettext('texts are written in double quotes, as in say "hello".'))
        elif character == ",":
            self._bad(number, position, character, gettext("values are separated by spaces, and decimals written with "
                                                           "a point (go_to 1.5 0.5)."))
        else:
            self._bad(number, position, character, gettext(
                '%(character)s has no meaning here; a command is words, numbers, "texts", { } and =.',
                character=repr(character)))
        return position + 1

    def _bad_word(self, line: str, number: int, start: int, end: int) -> int:
        while end < len(line) and (line[end] in _WORD_CHARACTERS or _is_other_letter(line[end])):
            end += 1
        word = line[start:end]
        self._bad(number, start, word, gettext('%(word)s: names use the letters a-z, digits and _ only (other letters '
                                               'may stand inside a quoted text, as in say "héllo").',
                                               word=repr(word[:40])))
        return end

    def _check_comment(self, line: str, number: int, position: int) -> None:
        for offset, character in enumerate(line[position:]):
            problem = character_problem(character)
            if problem:
                self._report(number, position + offset + 1, gettext("in a comment, %(problem)s.", problem=problem))
                return

    def _read_text(self, line: str, number: int, start: int) -> int:
        position, parts = start + 1, list[str]()
        while position < len(line):
            character = line[position]
            if character == '"':
                self.tokens.append(Token(Kind.TEXT, line[start:position + 1], number, start + 1, text="".join(parts)))
                return position + 1
            if character == "\\":
                following = line[position + 1:position + 2]
                if following not in _ESCAPES:
                    self._bad(number, position, "\\", gettext('in a text, \\ may only come before " or \\.'))
                    return _closing_quote(line, position + 1)
                parts.append(_ESCAPES[following])
                position += 2
                continue
            problem = text_character_problem(character)
            if problem:
                self._bad(number, position, character, gettext("in a text, %(problem)s.", problem=problem))
                return _closing_quote(line, position + 1)
            parts.append(character)
            position += 1
        self._bad(number, start, line[start:], gettext('this text has no closing " on its line.'))
        return len(line)

    def _read_number(self, line: str, number: int, start: int) -> int:
        position = start + 1 if line[start] in "+-" else start
        digits_start = position
        while position < len(line) and line[position] in _DIGITS:
            position += 1
        if position < len(line) and line[position] == ".":
            position += 1
            while position < len(line) and line[position] in _DIGITS:
                position += 1
        if (position < len(line) and line[position] in "eE" and _exponent_follows(line, position + 1)):
            position += 1 if line[position + 1] in _DIGITS else 2
            while position < len(line) and line[position] in _DIGITS:
                position += 1
        numeral = line[start:position]
        unit_start = position
        while position < len(line) and line[position] in _UNIT_CHARACTERS:
            position += 1
        unit = line[unit_start:position]
        end = position
        while end < len(line) and (line[end] in _WORD_CHARACTERS or line[end] in "./" or _is_other_letter(line[end])):
            end += 1
        written = line[start:end]
        if end > position or digits_start == position:
            self._bad(number, start, written, gettext("%(written)s is not a number (numbers are written 1.5, -2, 0.25, "
                                                      "3e-2, with a unit if any stuck to them: 90deg, 2s).",
                                                      written=repr(written[:40])))
            return end
        self.tokens.append(Token(Kind.NUMBER, written, number, start + 1, number=float(numeral), unit=unit))
        return end


def _starts_number(line: str, position: int) -> bool:
    rest = line[position + 1:position + 3] if line[position] in "+-" else line[position:position + 2]
    return bool(rest) and (rest[0] in _DIGITS or (rest[0] == "." and rest[1:2] in _DIGITS))


def _exponent_follows(line: str, position: int) -> bool:
    following = line[position:position + 2]
    return bool(following) and (following[0] in _DIGITS or (following[0] in "+-" and following[1:2] in _DIGITS))


def _is_other_letter(character: str) -> bool:
    return not character.isascii() and character.isalnum()


def _closing_quote(line: str, position: int) -> int:
    found = line.find('"', position)
    return len(line) if found < 0 else found + 1
