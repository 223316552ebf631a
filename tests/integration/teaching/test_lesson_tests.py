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
from tests.integration.bookings.conftest import client_as, course_people  # noqa: F401


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


def test_over_http_the_editor_names_a_bad_test_and_the_cues_wait_for_the_test_before(
        live_server, client_as, course_people) -> None:  # noqa: F811
    from pathlib import Path

    from middleware.db import session_factory
    from middleware.models import User
    from tests.integration.bookings.conftest import api

    folder = Path(live_server.app.instance_path) / "lessons"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "clip.webm").write_bytes(b"not really a video")
    with session_factory(live_server.app)() as session:
        tutor = session.get(User, course_people["tutor1"])
        question = bank.add_question(session, tutor, course_people["course"], parse_question(
            {"kind": "single", "prompt": "?", "choices": ["a", "b"], "correct": 0}))
        before = bank.create_exam(session, tutor, course_people["course"], parse_exam(
            {"title": "Before", "kind": "quiz", "question_ids": [question.id]})).id
        session.commit()
    tutor_client, student = client_as("tutor1"), client_as("student1")
    lesson = {"title": "Goal", "video_name": "clip.webm",
              "cues": 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"stop": true}\n'}
    for bad, field in (({"before_exam_id": "abc"}, "before_exam_id"), ({"after_exam_id": 10**9}, "after_exam_id"),
                       ({"before_exam_id": before, "after_exam_id": before}, "after_exam_id")):
        status, body = api(tutor_client, "POST", "/api/lessons", {**lesson, **bad})
        assert status == 400 and body["error"]["field"] == field, body
    assert api(client_as("tutor2"), "POST", "/api/lessons", {**lesson, "before_exam_id": before})[1]["error"][
        "field"] == "before_exam_id"  # a tutor of another course
    status, saved = api(tutor_client, "POST", "/api/lessons", {**lesson, "before_exam_id": str(before)})
    assert status == 201 and saved["before_exam_id"] == before
    status, body = api(student, "POST", f"/api/lessons/{saved['id']}/cues/1/run", {"target": "practice"})
    assert status == 409 and body["error"]["code"] == "before_test_required" and "“Before”" in body["error"]["message"]
    status, body = api(student, "GET", f"/api/lessons/{saved['id']}/results")
    assert status == 404 and body["error"]["code"] == "no_tests"  # no test after to compare with
