"""Deadlines on a controllable clock, one attempt at a time, immutability, overrides and recommendations.

Services are called with an explicit `now` on a migrated database (SQLite and PostgreSQL).
"""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.assessment import attempts, bank, recommendations, review
from middleware.assessment.attempts import TimeUp
from middleware.assessment.schemas import parse_exam, parse_question
from middleware.db import make_engine
from middleware.errors import Refused
from middleware.models import Course, CourseMembership, User
from middleware.models.assessment import Attempt
from tests.conftest import migrate_to_head

T0 = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)


@pytest.fixture
def world(database_url: str):
    """A course with a tutor, two students, one other tutor; two questions; a session."""
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    session = Session(engine, expire_on_commit=False)
    people = {}
    for name, role in [("s1", "student"), ("s2", "student"), ("t1", "tutor"), ("t2", "tutor")]:
        people[name] = User(username=name, role=role, password_hash="x")
    session.add_all(people.values())
    course, other = Course(code="ROB1", title="R1"), Course(code="ROB2", title="R2")
    session.add_all([course, other])
    session.flush()
    for name, course_id, role in [("s1", course.id, "student"), ("s2", course.id, "student"),
                                  ("t1", course.id, "tutor"), ("t2", other.id, "tutor")]:
        session.add(CourseMembership(course_id=course_id, user_id=people[name].id, role=role))
    q1 = bank.add_question(session, people["t1"], course.id, parse_question(
        {"kind": "single", "prompt": "Odometry drifts?", "choices": ["no", "yes"], "correct": 1,
         "topics": ["odometry"]}))
    q2 = bank.add_question(session, people["t1"], course.id, parse_question(
        {"kind": "numeric", "prompt": "Laser range?", "value": 5, "tolerance": 0.5, "unit": "m",
         "topics": ["sensors"]}))
    session.commit()
    yield session, people, course, (q1, q2)
    session.close()
    engine.dispose()


def _timed(session, tutor, course, questions, duration_s=60):
    return bank.create_exam(session, tutor, course.id, parse_exam({
        "title": "Midterm", "kind": "theory", "opens_at": T0.isoformat(),
        "closes_at": (T0 + timedelta(hours=1)).isoformat(), "duration_s": duration_s,
        "question_ids": [q.id for q in questions]}))


def test_an_answer_one_second_late_is_refused_and_the_attempt_is_submitted_as_it_stood(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0 + timedelta(seconds=5))
    session.commit()
    deadline = T0 + timedelta(seconds=65)
    attempts.save_answers(session, people["s1"], attempt.id, {str(questions[0].id): 1}, deadline)
    session.commit()
    with pytest.raises(TimeUp):
        attempts.save_answers(session, people["s1"], attempt.id, {str(questions[1].id): {"value": "5", "unit": "m"}},
                              deadline + timedelta(seconds=1))
    session.commit()  # what the route does: the automatic submission stands
    stored = session.get(Attempt, attempt.id)
    session.refresh(stored)
    assert stored.status == "submitted" and stored.submitted_by == "deadline"
    assert stored.auto_score == 1.0 and str(questions[1].id) not in stored.answers
    with pytest.raises(Refused) as again:
        attempts.submit_attempt(session, people["s1"], attempt.id, deadline + timedelta(seconds=2))
    assert again.value.code == "already_submitted"


def test_an_attempt_nobody_returns_to_is_submitted_at_the_deadline_by_the_next_look(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions, duration_s=30)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    attempts.save_answers(session, people["s1"], attempt.id, {str(questions[0].id): "1"}, T0 + timedelta(seconds=3))
    session.commit()
    rows = review.list_attempts(session, people["t1"], exam.id, T0 + timedelta(minutes=5))
    assert rows[0]["status"] == "submitted" and rows[0]["submitted_by"] == "deadline" and rows[0]["score"] == 1.0


def test_the_window_is_enforced_and_one_attempt_is_allowed(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions)
    session.commit()
    with pytest.raises(Refused) as early:
        attempts.start_attempt(session, people["s1"], exam.id, T0 - timedelta(seconds=1))
    assert early.value.code == "exam_upcoming"
    first = attempts.start_attempt(session, people["s1"], exam.id, T0)
    assert attempts.start_attempt(session, people["s1"], exam.id, T0 + timedelta(seconds=1)).id == first.id
    attempts.submit_attempt(session, people["s1"], first.id, T0 + timedelta(seconds=2))
    session.commit()
    with pytest.raises(Refused) as used:
        attempts.start_attempt(session, people["s1"], exam.id, T0 + timedelta(seconds=3))
    assert used.value.code == "no_attempts_left"
    with pytest.raises(Refused) as closed:
        attempts.start_attempt(session, people["s2"], exam.id, T0 + timedelta(hours=1))
    assert closed.value.code == "exam_closed"


def test_a_second_in_progress_attempt_is_refused_by_the_database(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions)
    session.add(Attempt(exam_id=exam.id, user_id=people["s1"].id, open_key=f"{exam.id}:{people['s1'].id}",
                        started_at=T0, answers={}))
    session.commit()
    session.add(Attempt(exam_id=exam.id, user_id=people["s1"].id, open_key=f"{exam.id}:{people['s1'].id}",
                        started_at=T0, answers={}))
    with pytest.raises(Exception, match="(?i)unique"):
        session.commit()
    session.rollback()


def test_tampering_is_refused(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    session.commit()
    for intruder in ("s2", "t1"):
        with pytest.raises(Refused) as refused:
            attempts.save_answers(session, people[intruder], attempt.id, {str(questions[0].id): 1}, T0)
        assert refused.value.status == 403
        session.rollback()
    with pytest.raises(Refused) as reading:
        review.attempt_view(session, people["s2"], attempt.id, T0)
    assert reading.value.status == 403
    with pytest.raises(Refused):
        review.attempt_view(session, people["t2"], attempt.id, T0)
    with pytest.raises(Refused) as foreign:
        attempts.save_answers(session, people["s1"], attempt.id, {"999": 1}, T0)
    assert foreign.value.status == 400
    session.rollback()
    attempts.submit_attempt(session, people["s1"], attempt.id, T0 + timedelta(seconds=10))
    session.commit()
    with pytest.raises(Refused) as changed:
        attempts.save_answers(session, people["s1"], attempt.id, {str(questions[0].id): 0}, T0 + timedelta(seconds=11))
    assert changed.value.code == "already_submitted"
    with pytest.raises(Refused) as override:
        review.override_mark(session, people["t2"], attempt.id, str(questions[0].id), 1, "x", "", T0)
    assert override.value.status == 403


def test_a_tutor_override_needs_a_reason_and_the_student_sees_it(world) -> None:
    session, people, course, questions = world
    exam = _timed(session, people["t1"], course, questions)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    attempts.submit_attempt(session, people["s1"], attempt.id, T0 + timedelta(seconds=10),
                            {str(questions[1].id): {"value": "5.6", "unit": "m"}})
    session.commit()
    item = str(questions[1].id)
    with pytest.raises(Refused):
        review.override_mark(session, people["t1"], attempt.id, item, 1, " ", "", T0)
    with pytest.raises(Refused):
        review.override_mark(session, people["t1"], attempt.id, item, 5, "too much", "", T0)
    review.override_mark(session, people["t1"], attempt.id, item, 0.5, "Right method, rounding slip", "Close!", T0)
    session.commit()
    view = review.attempt_view(session, people["s1"], attempt.id, T0 + timedelta(minutes=1))
    changed = next(r for r in view["results"] if r["item"] == item)
    assert changed["points"] == 0.5 and changed["auto_points"] == 0 and "rounding" in changed["override_reason"]
    assert view["score"] == 0.5 and view["reviews"][0]["comment"] == "Close!"
    assert "trace" not in view
    csv_text = review.grades_csv(session, people["t1"], course.id, T0 + timedelta(minutes=1))
    assert "s1,0.5" in csv_text


def test_recommendations_follow_the_weak_topics(world) -> None:
    session, people, course, questions = world
    quiz = bank.create_exam(session, people["t1"], course.id, parse_exam(
        {"title": "Sensors practice", "kind": "quiz", "question_ids": [questions[1].id]}))
    exam = _timed(session, people["t1"], course, questions)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    attempts.submit_attempt(session, people["s1"], attempt.id, T0 + timedelta(seconds=5),
                            {str(questions[0].id): 1, str(questions[1].id): {"value": "9", "unit": "m"}})
    session.commit()
    scores = {s.topic: s.ratio for s in recommendations.topic_scores(session, people["s1"].id, course.id)}
    assert scores == {"odometry": 1.0, "sensors": 0.0}
    recs = recommendations.recommend(session, people["s1"].id, course.id, T0)
    assert [(r.kind, r.topic, r.href) for r in recs] == [("practice_quiz", "sensors", f"/assessment/exams/{quiz.id}")]
    assert recommendations.recommend(session, people["s2"].id, course.id, T0) == []
    assert session.scalar(select(Attempt.id).where(Attempt.user_id == people["s2"].id)) is None
