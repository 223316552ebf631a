"""A course's survey: statements rated 1-5 with labelled ends. The 2003 paper's seven, or ones its tutor writes.

Pure: parsing of the tutor's statements (every bad line named) and of a student's answers to them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.assessment.rating import DEFAULT_ENDS, read_ends, read_rating
from middleware.auth.schemas import InvalidField

SURVEY_ITEMS = (
    ("objectives_clear", "The learning objectives were clear"),
    ("well_presented", "The course was well presented"),
    ("lab_accessible", "The lab was easily accessible"),
    ("corrections_helpful", "The corrected exercises contained helpful comments"),
    ("system_essential", "The system was essential to the course"),
    ("system_reliable", "The system was reliable"),
    ("easy_to_use", "The system was easy to use"),
)
AGREEMENT = ("Strongly disagree", "Disagree", "Neutral", "Agree", "Strongly agree")
DEFAULT_TITLE = "Evaluate the lab"
MAX_STATEMENTS = 30
MAX_STATEMENT = 300
MAX_TITLE = 120


@dataclass(frozen=True)
class Statement:
    """One statement of a survey, its answers' key, and what 1 and 5 mean."""

    key: str
    text: str
    low_label: str = DEFAULT_ENDS[0]
    high_label: str = DEFAULT_ENDS[1]

    def to_dict(self) -> dict[str, str]:
        """The JSON form."""
        return asdict(self)


FIXED_STATEMENTS = tuple(Statement(key, text) for key, text in SURVEY_ITEMS)


def _statement_text(value: object, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InvalidField("statements", gettext("statements: %(where)s needs the statement's text.", where=where))
    text = " ".join(value.split())
    if len(text) > MAX_STATEMENT:
        raise InvalidField("statements", gettext("statements: %(where)s is longer than %(max_statement)s characters.",
                                                 where=where, max_statement=MAX_STATEMENT))
    return text


def _from_line(line: str, number: int) -> dict[str, Any]:
    """"Statement | what 1 means | what 5 means" (the ends optional) as the API's object."""
    parts = [part.strip() for part in line.split("|")]
    if len(parts) > 3:
        raise InvalidField("statements", gettext("statements: line %(number)s has more than two '|'; write "
                                                 "'statement | what 1 means | what 5 means'.", number=number))
    return dict(zip(("text", "low_label", "high_label"), parts, strict=False))


def parse_statements(value: object) -> list[Statement]:
    """The statements of a tutor's survey: a list of {text, low_label, high_label}, or text with one statement per
    line ("text | what 1 means | what 5 means"); keys s1, s2, ... in order. InvalidField names the line at fault."""
    if isinstance(value, str):
        lines = [(n, line) for n, line in enumerate(value.splitlines(), start=1) if line.strip()]
        items: list[tuple[str, object]] = [(f"line {n}", _from_line(line, n)) for n, line in lines]
    elif isinstance(value, list):
        items = [(f"statement {n}", item) for n, item in enumerate(value, start=1)]
    else:
        raise InvalidField("statements", gettext("statements must be a list of statements, or text with one per "
                                                 "line."))
    if not items:
        raise InvalidField("statements", gettext("Write at least one statement for the students to rate."))
    if len(items) > MAX_STATEMENTS:
        raise InvalidField("statements", gettext("A survey has at most %(max_statements)s statements.",
                                                 max_statements=MAX_STATEMENTS))
    out = []
    for number, (where, item) in enumerate(items, start=1):
        if not isinstance(item, dict):
            raise InvalidField("statements", gettext("statements: %(where)s must be an object with its text.",
                                                     where=where))
        try:
            ends = read_ends(item)
        except InvalidField as invalid:
            raise InvalidField("statements", gettext("statements: %(where)s: %(message)s", where=where,
                                                     message=invalid.message)) from None
        out.append(Statement(f"s{number}", _statement_text(item.get("text"), where), **ends))
    return out


def parse_title(value: object) -> str:
    """The survey's title as its students read it; the default when not given."""
    if value in (None, ""):
        return DEFAULT_TITLE
    if not isinstance(value, str) or not value.strip() or len(value.strip()) > MAX_TITLE:
        raise InvalidField("title", gettext("title must be text of 1 to %(max_title)s characters.",
                                            max_title=MAX_TITLE))
    return " ".join(value.split())


def statements_text(statements: Sequence[Statement]) -> str:
    """The editor's text of stored statements, which parse_statements reads back."""
    return "\n".join(f"{s.text} | {s.low_label} | {s.high_label}" for s in statements)


def parse_answers(data: dict[str, Any], statements: Sequence[Statement]) -> tuple[dict[str, int], str]:
    """Ratings 1-5 for every statement, and free comments (up to 4000 characters)."""
    source = data.get("ratings") if isinstance(data.get("ratings"), dict) else data
    ratings = {s.key: read_rating(source.get(s.key), s.key) for s in statements}  # type: ignore[union-attr]
    comments = data.get("comments") or ""
    if not isinstance(comments, str) or len(comments) > 4000:
        raise InvalidField("comments", gettext("comments must be text of at most 4000 characters."))
    return ratings, comments.strip()
