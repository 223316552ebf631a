"""A lesson's tests before and after on a migrated database (SQLite and PostgreSQL): the robot waits for the test
before, a test the author does not teach is refused naming the field, and the comparison per part is the student's
own or, for the tests' tutor, the class's."""

from __future__ import annotations

from datetime import timedelta

import pytest

from middleware.assessment import attempts, bank
from middleware.assessment.schemas import parse_exam, parse_question
from middleware.errors import Refused
from middleware.models.teaching import Lesson
from middleware.teaching.lesson_tests import check_lesson_tests, lesson_gate, lesson_results, require_before_test
from tests.integration.assessment.test_attempt_rules import T0, world  # noqa: F401


def _take(session, student, exam_id: int, answers: dict, at) -> None:
    attempt = attempts.start_attempt(session, student, exam_id, at)
    attempts.save_answers(session, student, attempt.id, answers, at + timedelta(seconds=1))
    attempts.submit_attempt(session, student, attempt.id, at + timedelta(seconds=2))
    session.commit()


def test_the_robot_waits_for_the_test_before_and_the_parts_compare(world) -> None:  # noqa: F811
    session, people, course, (q1, _q2) = world
    tutor, student = people["t1"], people["s1"]
    rating = bank.add_question(session, tutor, course.id, parse_question(
        {"kind": "rating", "prompt": "Part 1 helped me", "topics": ["odometry"]}))
    before = bank.create_exam(session, tutor, course.id, parse_exam(
        {"title": "Before", "kind": "quiz", "question_ids": [q1.id]}))
    after = bank.create_exam(session, tutor, course.id, parse_exam(
        {"title": "After", "kind": "quiz", "question_ids": [q1.id, rating.id]}))
    with pytest.raises(Refused) as refused:
        check_lesson_tests(session, people["t2"], before.id, after.id)  # t2 teaches another course
    assert refused.value.field == "before_exam_id"
    with pytest.raises(Refused) as refused:
        check_lesson_tests(session, tutor, before.id, before.id)
    assert refused.value.field == "after_exam_id"
    check_lesson_tests(session, tutor, before.id, after.id)
    lesson = Lesson(slug="l", title="L", video_name="v.webm", cues_vtt="WEBVTT\n", before_exam_id=before.id,
                    after_exam_id=after.id)
    session.add(lesson)
    session.commit()

    with pytest.raises(Refused) as refused:
        require_before_test(session, lesson, student)
    assert (refused.value.status, refused.value.code) == (409, "before_test_required")
    require_before_test(session, lesson, tutor)  # the author is never held back
    _take(session, student, before.id, {str(q1.id): 0}, T0)  # wrong before
    require_before_test(session, lesson, student)
    assert lesson_results(session, lesson, student).students == 0
    _take(session, student, after.id, {str(q1.id): 1, str(rating.id): 4}, T0 + timedelta(minutes=5))
    assert lesson_gate(session, lesson, student).after_done

    mine = lesson_results(session, lesson, student)
    row = next(p for p in mine.parts if p.part == "odometry")
    assert (mine.whose, mine.students, row.before, row.after, row.change, row.rating_after) == (
        "yours", 1, 0.0, 1.0, 1.0, 4.0)
    assert lesson_results(session, lesson, people["s2"]).students == 0  # another student sees only their own
    assert (lesson_results(session, lesson, tutor).whose, lesson_results(session, lesson, tutor).students) == (
        "class", 1)
