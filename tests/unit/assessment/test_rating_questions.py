"""A rating question: 1-5 with labelled ends, never marked; anything outside 1-5 is refused naming the field."""

from __future__ import annotations

import pytest

from middleware.assessment.grading import grade_question
from middleware.assessment.rating import read_rating, scale
from middleware.assessment.schemas import parse_question
from middleware.auth.schemas import InvalidField


def test_a_rating_question_keeps_its_labelled_ends_and_the_agreement_scale_by_default() -> None:
    labelled = parse_question({"kind": "rating", "prompt": "Did the robot's sound help?", "low_label": "Not at all",
                               "high_label": "  A great   deal "})
    assert labelled.spec == {"low_label": "Not at all", "high_label": "A great deal"}
    plain = parse_question({"kind": "rating", "prompt": "Was part 2 effective?"})
    assert plain.spec == {"low_label": "Strongly disagree", "high_label": "Strongly agree"}
    assert [p["label"] for p in scale(plain.spec)] == ["Strongly disagree", "", "", "", "Strongly agree"]


@pytest.mark.parametrize("ends", [{"low_label": "x" * 61}, {"high_label": 5}, {"low_label": "   "}])
def test_an_end_label_that_is_not_short_text_is_refused_naming_it(ends) -> None:
    with pytest.raises(InvalidField) as refused:
        parse_question({"kind": "rating", "prompt": "Rate it", **ends})
    assert refused.value.field in ends


@pytest.mark.parametrize("answer, rating", [(1, 1), (5, 5), ("3", 3)])
def test_a_rating_is_shown_and_earns_nothing_out_of_nothing(answer, rating) -> None:
    result = grade_question("7", "rating", {"low_label": "a", "high_label": "b"}, 1.0, answer)
    assert (result.points, result.max_points, result.correct) == (0.0, 0.0, True)
    assert f"Rated {rating} of 5" in result.feedback


@pytest.mark.parametrize("value", [0, 6, -1, "6", "٣", "3.5", 3.5, True, None, "", [3], "five"])
def test_a_rating_outside_one_to_five_is_refused_naming_the_field(value) -> None:
    with pytest.raises(InvalidField) as refused:
        read_rating(value, "part_1")
    assert refused.value.field == "part_1"
    assert "1 to 5" in refused.value.message


def test_an_unanswered_rating_says_so_and_still_moves_no_mark() -> None:
    result = grade_question("7", "rating", {}, 1.0, None)
    assert (result.points, result.max_points, result.correct) == (0.0, 0.0, False)
