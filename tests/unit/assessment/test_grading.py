"""Automatic grading of every question type, experimental runs against a rubric, survey aggregation."""

from __future__ import annotations

import math

import pytest

from middleware.assessment.grading import grade_question
from middleware.assessment.schemas import parse_bank_file, parse_question
from middleware.assessment.survey import aggregate
from middleware.assessment.trace_grading import band_fraction, grade_task
from middleware.auth.schemas import InvalidField

SINGLE = {"choices": ["a", "b", "c"], "correct": 1}
MULTIPLE = {"choices": ["a", "b", "c", "d"], "correct": [0, 2]}
NUMERIC = {"value": 0.5, "tolerance": 0.05, "unit": "m"}
TEXT = {"accepted": ["Dead reckoning", "odometry"], "case_sensitive": False}


@pytest.mark.parametrize(("kind", "spec", "answer", "points"), [
    ("single", SINGLE, 1, 2), ("single", SINGLE, "1", 2), ("single", SINGLE, 0, 0), ("single", SINGLE, None, 0),
    ("single", SINGLE, True, 0),
    ("multiple", MULTIPLE, [0, 2], 2), ("multiple", MULTIPLE, [2, 0], 2), ("multiple", MULTIPLE, [0], 1),
    ("multiple", MULTIPLE, [0, 1], 0), ("multiple", MULTIPLE, [0, 1, 2, 3], 0), ("multiple", MULTIPLE, [], 0),
    ("multiple", MULTIPLE, [9], 0),
    ("numeric", NUMERIC, {"value": "0.55", "unit": "m"}, 2), ("numeric", NUMERIC, {"value": "0.45", "unit": "m"}, 2),
    ("numeric", NUMERIC, {"value": "0.5501", "unit": "m"}, 0), ("numeric", NUMERIC, {"value": "55", "unit": "cm"}, 2),
    ("numeric", NUMERIC, {"value": "0,5", "unit": "m"}, 2), ("numeric", NUMERIC, {"value": "0.5", "unit": "s"}, 0),
    ("numeric", NUMERIC, {"value": "", "unit": "m"}, 0),
    ("numeric", NUMERIC, {"value": "nan", "unit": "m"}, 0), ("numeric", NUMERIC, {"value": "inf", "unit": "m"}, 0),
    ("numeric", {"value": 90, "tolerance": 1, "unit": "deg"}, {"value": str(math.pi / 2), "unit": "rad"}, 2),
    ("numeric", NUMERIC, {"value": "0.5", "unit": "furlong"}, 0),
    ("text", TEXT, "  dead   RECKONING ", 2), ("text", TEXT, "odometer", 0), ("text", TEXT, "", 0),
    ("text", TEXT, "   ", 0),
])
def test_every_question_type_is_graded_with_its_edge_cases(kind, spec, answer, points) -> None:
    result = grade_question("1", kind, spec, 2.0, answer)
    assert result.points == points, result.feedback
    assert result.max_points == 2.0


@pytest.mark.parametrize("answer", [{"value": "0.52", "unit": ""}, {"value": "0.52", "unit": "  "}, {"value": "0.52"},
                                    "0.52"])
def test_a_bare_number_is_read_in_the_question_s_own_unit(answer: object) -> None:
    result = grade_question("1", "numeric", NUMERIC, 2.0, answer)
    assert (result.points, result.feedback) == (2.0, "Correct (0.5 ± 0.05 m).")
    assert grade_question("1", "numeric", NUMERIC, 2.0, {"value": "52"}).points == 0  # 52 m, not 52 cm


def test_empty_answers_say_so() -> None:
    assert grade_question("1", "text", TEXT, 1, None).feedback == "No answer."


def test_unknown_question_types_are_refused_on_import_and_by_the_grader() -> None:
    with pytest.raises(ValueError):
        grade_question("1", "essay", {}, 1, "x")
    with pytest.raises(InvalidField) as error:
        parse_bank_file(b'{"questions": [{"kind": "single", "prompt": "p", "choices": ["a","b"], "correct": 0},'
                        b' {"kind": "essay", "prompt": "p"}, {"kind": "numeric", "prompt": "p", "value": "x"}]}')
    assert "question 2: kind" in error.value.message and "question 3: value" in error.value.message


def test_bank_files_are_size_limited_and_must_be_json() -> None:
    with pytest.raises(InvalidField):
        parse_bank_file(b"{" + b" " * 600_000 + b"}")
    with pytest.raises(InvalidField):
        parse_bank_file(b"not json")


def test_a_question_round_trips_through_the_file_form() -> None:
    question = parse_question({"kind": "numeric", "prompt": "Wheel base?", "value": "0.3", "tolerance": "0.01",
                               "unit": "m", "topics": "Kinematics, odometry"})
    again = parse_question(question.to_dict())
    assert again == question and question.topics == ["kinematics", "odometry"]


def _run(points: list[tuple[float, float]]) -> list[list[float]]:
    return [[i * 0.2, x, y, 0.0, x, y, 0.0] for i, (x, y) in enumerate(points)]


REACH = {"kind": "reach_point", "x_m": 1.0, "y_m": 0.0, "rubric": [[0.1, 1.0], [0.2, 0.5], [0.4, 0.25]]}


@pytest.mark.parametrize(("end", "points"), [((0.95, 0.0), 10), ((1.0, 0.1), 10), ((0.85, 0.0), 5),
                                             ((0.7, 0.0), 2.5), ((0.0, 0.0), 0)])
def test_reach_point_runs_pass_partly_pass_and_fail(end, points) -> None:
    result = grade_task(REACH, 10, _run([(0, 0), (0.5, 0), end]), None)
    assert result.points == points, result.feedback


def test_an_empty_run_scores_nothing() -> None:
    assert grade_task(REACH, 10, [], None).points == 0


def test_wall_following_uses_the_rms_error_and_needs_travel() -> None:
    task = {"kind": "wall_following", "x1_m": 0, "y1_m": 1, "x2_m": 5, "y2_m": 1, "distance_m": 0.5,
            "min_travel_m": 1.0, "rubric": [[0.05, 1.0], [0.15, 0.5]]}
    good = _run([(x / 10, 0.5 + (0.02 if x % 2 else -0.02)) for x in range(30)])
    wobbly = _run([(x / 10, 0.5 + (0.1 if x % 2 else -0.1)) for x in range(30)])
    parked = _run([(0, 0.5)] * 30)
    assert grade_task(task, 4, good, None).points == 4
    assert grade_task(task, 4, wobbly, None).points == 2
    assert grade_task(task, 4, parked, None).points == 0


def test_a_reported_pose_is_compared_with_the_ground_truth_at_the_report() -> None:
    task = {"kind": "report_pose", "rubric": [[0.1, 1.0]]}
    trace = _run([(0, 0), (1, 0), (2, 0)])  # t = 0, 0.2, 0.4
    assert grade_task(task, 1, trace, {"x_m": "1.05", "y_m": "0", "t_s": 0.21}).points == 1
    assert grade_task(task, 1, trace, {"x_m": "1.05", "y_m": "0", "t_s": 0.4}).points == 0
    assert grade_task(task, 1, trace, None).points == 0


def test_rubric_bounds_are_inclusive() -> None:
    assert band_fraction([[0.1, 1.0]], 0.1) == 1.0
    assert band_fraction([[0.1, 1.0]], 0.1001) == 0.0


def test_survey_answers_are_counted_per_question() -> None:
    items = aggregate([{"objectives_clear": 5, "easy_to_use": 4}, {"objectives_clear": 4}, {"objectives_clear": 9}])
    first = items[0]
    assert first.key == "objectives_clear" and first.counts == (0, 0, 0, 1, 1) and first.percentages()[4] == 50
    assert len(items) == 7 and items[-1].counts == (0, 0, 0, 1, 0)


def test_the_editors_rubric_rows_become_bands_and_every_bad_row_is_named() -> None:
    from middleware.assessment.schemas import form_rubric
    from middleware.auth.schemas import InvalidField

    rows = {"rubric_bound_0": "0.1", "rubric_share_0": "100", "rubric_bound_1": " 0.3 ", "rubric_share_1": "50",
            "rubric_bound_2": "", "rubric_share_2": ""}
    assert form_rubric(rows) == [[0.1, 1.0], [0.3, 0.5]]
    assert form_rubric({"rubric": "0.1:1"}) == "0.1:1"  # the API's form is kept as sent
    with pytest.raises(InvalidField) as refused:
        form_rubric({**rows, "rubric_share_1": "half", "rubric_bound_3": "0.5"})
    assert refused.value.field == "rubric"
    assert "row 2" in refused.value.message and "row 4" in refused.value.message
