"""A tutor's survey: statements with labelled ends, every bad line named; answers must rate each statement 1-5."""

from __future__ import annotations

import pytest

from middleware.assessment.survey_statements import (
    FIXED_STATEMENTS,
    parse_answers,
    parse_statements,
    parse_title,
    statements_text,
)
from middleware.auth.schemas import InvalidField


def test_statements_from_lines_carry_their_ends_and_read_back() -> None:
    text = ("Part 1 (the robot drives slowly) helped me learn\n\n"
            "Part 3 (the robot's sound) helped me learn | Not at all | A great deal\n")
    statements = parse_statements(text)
    assert [(s.key, s.low_label, s.high_label) for s in statements] == [
        ("s1", "Strongly disagree", "Strongly agree"), ("s2", "Not at all", "A great deal")]
    assert parse_statements(statements_text(statements)) == statements
    assert parse_statements([{"text": "Clear", "high_label": "Very"}])[0].high_label == "Very"


@pytest.mark.parametrize("value, names", [
    ("", "at least one statement"), ("  \n \n", "at least one statement"), ([], "at least one statement"),
    ("ok\n | Low | High", "line 2 needs the statement's text"), ("a | b | c | d", "line 1 has more than two"),
    ("x" * 301, "line 1 is longer than 300"), ("\n".join(["s"] * 31), "at most 30"),
    ([{"text": "ok"}, "text"], "statement 2 must be an object"), ({"text": "x"}, "must be a list"),
    ([{"text": "ok", "low_label": "L" * 61}], "statement 1: low_label"),
])
def test_a_survey_that_cannot_be_rated_is_refused_naming_the_statements_field(value, names) -> None:
    with pytest.raises(InvalidField) as refused:
        parse_statements(value)
    assert refused.value.field == "statements" and names in refused.value.message


def test_every_statement_needs_a_rating_from_one_to_five() -> None:
    statements = parse_statements("A\nB | no | yes")
    assert parse_answers({"s1": "5", "s2": 1, "comments": " ok "}, statements) == ({"s1": 5, "s2": 1}, "ok")
    for bad in ({"s1": 5}, {"s1": 5, "s2": 6}, {"s1": 0, "s2": 1}, {"s1": "٣", "s2": 1}):
        with pytest.raises(InvalidField) as refused:
            parse_answers(bad, statements)
        assert refused.value.field in ("s1", "s2")


def test_the_fixed_survey_is_the_2003_papers_seven_statements_and_the_title_has_a_default() -> None:
    assert len(FIXED_STATEMENTS) == 7 and FIXED_STATEMENTS[0].key == "objectives_clear"
    assert parse_title("") == "Evaluate the lab" and parse_title("  After  the lesson ") == "After the lesson"
    with pytest.raises(InvalidField):
        parse_title("t" * 121)
