"""Text already in the database that a page cannot show as typed (a lone surrogate, NUL, 100 kB, a script
tag), written straight into every text field a person can save: every page and download that shows it still
answers 200, with the text escaped or replaced, never a 500."""

from __future__ import annotations

import json

import pytest
from sqlalchemy import select, update

from tests.hardening.conftest import logged_in_client

SCRIPT = "<script>alert(1)</script>"
LONE_SURROGATE = "\ud800"
HOSTILE = f"{SCRIPT} a{LONE_SURROGATE}b c\x00d " + "x" * 100_000
STORABLE_HOSTILE = HOSTILE.replace(LONE_SURROGATE, "")  # what a text column can hold at all (drivers refuse the rest)


@pytest.fixture(scope="module")
def spoiled_lab(hostile_lab):
    """The seeded lab with a started attempt, a comment, a chat message and a survey answer, then every text
    field filled with hostile text in the database; the ids the pages need."""
    from middleware.db import session_factory
    from middleware.models import (
        Attempt,
        AttemptReview,
        ChatMessage,
        Course,
        Exam,
        Question,
        SurveyResponse,
        Tour,
    )

    student, tutor = logged_in_client(hostile_lab, "student"), logged_in_client(hostile_lab, "tutor")
    with session_factory(hostile_lab)() as session:
        course = session.scalars(select(Course)).one()
        exam = session.scalars(select(Exam).where(Exam.kind == "theory", Exam.course_id == course.id)).first()
        question_ids = list(exam.question_ids)
    started = student.post(f"/api/exams/{exam.id}/attempts", json={})
    assert started.status_code in (200, 201), started.get_data(as_text=True)[:300]
    attempt_id = started.get_json()["attempt"]["id"]
    assert student.post(f"/api/courses/{course.id}/survey", json={"comments": "fine", **{
        key: 3 for key in _survey_keys(hostile_lab, course.id)}}).status_code in (200, 201)
    assert student.post("/api/robots/lab-1/chat", json={"body": "hello"}).status_code in (200, 201)
    with session_factory(hostile_lab)() as session:  # as a student's answer was saved before the edge refused it
        answers = {str(qid): HOSTILE for qid in question_ids}
        session.execute(update(Attempt).where(Attempt.id == attempt_id).values(answers=answers))
        session.commit()
    assert student.post(f"/api/attempts/{attempt_id}/submit", json={}).status_code == 200
    assert tutor.post(f"/api/attempts/{attempt_id}/comments", json={"comment": "ok"}).status_code == 201

    with session_factory(hostile_lab)() as session:
        for question in session.scalars(select(Question)):
            spec = dict(question.spec)
            if "choices" in spec:
                spec["choices"] = [HOSTILE for _ in spec["choices"]]
            question.spec, question.prompt = spec, STORABLE_HOSTILE
            question.topics = [f"topic {LONE_SURROGATE}", SCRIPT]
        session.execute(update(Course).values(title=STORABLE_HOSTILE[:200]))
        for test in session.scalars(select(Exam)):
            test.title = STORABLE_HOSTILE[:200]
            if test.task:
                test.task = {**test.task, "instructions": HOSTILE}
        session.execute(update(AttemptReview).values(comment=STORABLE_HOSTILE))
        session.execute(update(SurveyResponse).values(comments=STORABLE_HOSTILE))
        session.execute(update(ChatMessage).values(body=STORABLE_HOSTILE))
        for tour in session.scalars(select(Tour)):
            steps = json.loads(tour.steps_json)
            for step in steps:
                step["text"], step["title"] = HOSTILE[:2000], HOSTILE[:120]  # the longest a tour could save
            tour.steps_json = json.dumps(steps)
            tour.title, tour.summary, tour.topics = STORABLE_HOSTILE[:120], STORABLE_HOSTILE[:500], STORABLE_HOSTILE
        session.commit()
        tour_id = session.scalars(select(Tour.id)).first()
    return {"course": course.id, "exam": exam.id, "attempt": attempt_id, "tour": tour_id}


def _survey_keys(app, course_id: int) -> list[str]:
    """The keys of the statements the course's survey asks (the demo tutor wrote its own)."""
    from middleware.assessment.survey import survey_of
    from middleware.db import session_factory

    with session_factory(app)() as session:
        return [statement.key for statement in survey_of(session, course_id).statements]


PAGES = {
    "student": ("/assessment", "/assessment/exams/{exam}", "/assessment/attempts/{attempt}", "/api/attempts/{attempt}",
                "/teaching", "/tours/{tour}", "/api/tours/{tour}", "/api/robots/lab-1/chat",
                "/api/courses/{course}/recommendations", "/lab"),
    "tutor": ("/assessment", "/courses/{course}/assessment", "/api/courses/{course}/bank.json",
              "/api/courses/{course}/questions", "/assessment/exams/{exam}", "/assessment/attempts/{attempt}",
              "/api/attempts/{attempt}", "/courses/{course}", "/courses/{course}/grades.csv",
              "/api/courses/{course}/grades.csv", "/courses/{course}/survey/results",
              "/api/courses/{course}/survey/results", "/courses/{course}/assessment?question=1", "/teaching",
              "/tours/{tour}", "/tours/{tour}/edit", "/api/robots/lab-1/chat", "/courses"),
}


@pytest.mark.parametrize(("role", "page"), [(role, page) for role, pages in PAGES.items() for page in pages])
def test_page_shows_stored_hostile_text_escaped(spoiled_lab, role_clients, role: str, page: str) -> None:
    answer = role_clients[role].get(page.format(**spoiled_lab))
    assert answer.status_code == 200, f"{page}: {answer.status_code} {answer.get_data(as_text=True)[:300]}"
    text = answer.get_data().decode("utf-8")  # the bytes sent are valid UTF-8
    if answer.mimetype == "text/html":
        assert SCRIPT not in text, f"{page} shows stored text unescaped"
