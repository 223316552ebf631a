"""A quiz with a rating question on a migrated database (SQLite and PostgreSQL): the rating is stored, a rating
outside 1-5 is refused naming the question, and the rating moves neither the mark nor the weak topics."""

from __future__ import annotations

from datetime import timedelta

import pytest

from middleware.assessment import attempts, bank, recommendations
from middleware.assessment.schemas import parse_exam, parse_question
from middleware.errors import Refused
from tests.integration.assessment.test_attempt_rules import T0, world  # noqa: F401


def test_a_rating_is_stored_refused_outside_the_scale_and_never_marked(world) -> None:  # noqa: F811
    session, people, course, (q1, _q2) = world
    rating = bank.add_question(session, people["t1"], course.id, parse_question(
        {"kind": "rating", "prompt": "Coordination part 3 (the sound) helped me learn", "topics": ["sound"],
         "low_label": "Strongly disagree", "high_label": "Strongly agree"}))
    exam = bank.create_exam(session, people["t1"], course.id, parse_exam(
        {"title": "After the lesson", "kind": "quiz", "question_ids": [q1.id, rating.id]}))
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    session.commit()
    for bad in (6, 0, "9", "x"):
        with pytest.raises(Refused) as refused:
            attempts.save_answers(session, people["s1"], attempt.id, {str(rating.id): bad}, T0 + timedelta(seconds=1))
        session.rollback()
        assert refused.value.status == 400 and refused.value.field == str(rating.id)
    attempts.save_answers(session, people["s1"], attempt.id, {str(rating.id): "2", str(q1.id): 1},
                          T0 + timedelta(seconds=2))
    done = attempts.submit_attempt(session, people["s1"], attempt.id, T0 + timedelta(seconds=3))
    session.commit()
    assert done.answers[str(rating.id)] == 2
    assert (done.auto_score, done.max_score) == (1.0, 1.0)
    assert "sound" not in [t.topic for t in recommendations.topic_scores(session, people["s1"].id, course.id)]
    student_view = bank.question_dict(rating, with_key=False)
    assert (student_view["low_label"], student_view["high_label"]) == ("Strongly disagree", "Strongly agree")
