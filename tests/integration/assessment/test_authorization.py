"""Every assessment endpoint against every role: refused with the right status, and nothing changed.

Roles: anonymous, student1 (owns the attempt, in ROB1), student2 (another student of ROB1), tutor1 (tutor of ROB1),
tutor2 (tutor of ROB2 only), admin1. Pages answer 403 (anonymous: a redirect to the login page); the API 401/403.
"""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import LabClient
from tests.integration.accounts.test_authorization import _fill
from tests.integration.bookings.conftest import api

ALL = {"student1", "student2", "tutor1", "tutor2", "admin1"}
TEACH = {"tutor1", "admin1"}
STUDENTS = {"student1", "student2"}
OWNER = {"student1"}
READ_ATTEMPT = {"student1", "tutor1", "admin1"}
QUESTION = {"kind": "text", "prompt": "p", "accepted": ["a"]}

# (method, path, allowed, body). {c}: ROB1, {q}: a question, {e}: a timed test, {a}: student1's submitted attempt,
# {o}: student1's attempt in progress at the quiz {z}.
PAGES = [
    ("GET", "/courses/{c}/assessment", TEACH, None),
    ("POST", "/courses/{c}/assessment/questions", TEACH, {"kind": "text", "prompt": "p", "accepted": "a"}),
    ("POST", "/courses/{c}/assessment/exams", TEACH, {"title": "t", "kind": "quiz", "question_ids": "{q}"}),
    ("GET", "/courses/{c}/assessment?question={q}", TEACH, None),
    ("GET", "/courses/{c}/assessment?exam={e}", TEACH, None),
    ("POST", "/courses/{c}/assessment/questions/{q}", TEACH, {"kind": "text", "prompt": "p", "accepted": "a"}),
    ("POST", "/courses/{c}/assessment/questions/{q}/delete", TEACH, {}),
    ("POST", "/courses/{c}/assessment/exams/{z}", TEACH, {"title": "t", "kind": "quiz", "question_ids": "{q}"}),
    ("POST", "/courses/{c}/assessment/exams/{z}/delete", TEACH, {}),
    ("GET", "/assessment/exams/{e}", ALL - {"tutor2"}, None),
    ("POST", "/assessment/exams/{z}/start", STUDENTS, {}),
    ("GET", "/assessment/attempts/{a}", READ_ATTEMPT, None),
    ("POST", "/assessment/attempts/{o}/submit", OWNER, {}),
    ("POST", "/assessment/attempts/{a}/override", TEACH, {"item": "{q}", "points": "0", "reason": "r"}),
    ("POST", "/assessment/attempts/{a}/comment", TEACH, {"comment": "c"}),
    ("GET", "/courses/{c}/grades.csv", TEACH, None),
    ("GET", "/courses/{c}/survey", STUDENTS, None),
    ("GET", "/courses/{c}/survey/results", TEACH, None),
]
APIS = [
    ("GET", "/api/courses/{c}/questions", TEACH, None),
    ("POST", "/api/courses/{c}/questions", TEACH, QUESTION),
    ("PUT", "/api/questions/{q}", TEACH, QUESTION),
    ("DELETE", "/api/questions/{q}", TEACH, None),
    ("GET", "/api/courses/{c}/bank.json", TEACH, None),
    ("POST", "/api/courses/{c}/bank", TEACH, {"questions": [QUESTION]}),
    ("GET", "/api/courses/{c}/exams", ALL - {"tutor2"}, None),
    ("POST", "/api/courses/{c}/exams", TEACH, {"title": "t", "kind": "quiz", "question_ids": ["{q}"]}),
    ("PUT", "/api/exams/{e}", TEACH, {"title": "t", "kind": "quiz", "question_ids": ["{q}"]}),
    ("DELETE", "/api/exams/{z}", TEACH, None),
    ("GET", "/api/exams/{e}/attempts", TEACH, None),
    ("POST", "/api/exams/{z}/attempts", STUDENTS, None),
    ("GET", "/api/attempts/{a}", READ_ATTEMPT, None),
    ("PATCH", "/api/attempts/{o}/answers", OWNER, {"answers": {"{q}": "a"}}),
    ("POST", "/api/attempts/{o}/submit", OWNER, {}),
    ("POST", "/api/attempts/{a}/overrides", TEACH, {"item": "{q}", "points": 0, "reason": "r"}),
    ("POST", "/api/attempts/{a}/comments", TEACH, {"comment": "c"}),
    ("GET", "/api/courses/{c}/grades.csv", TEACH, None),
    ("GET", "/api/courses/{c}/recommendations", STUDENTS, None),
    ("POST", "/api/courses/{c}/survey", STUDENTS, {"ratings": {}}),
    ("GET", "/api/courses/{c}/survey/results", TEACH, None),
]


@pytest.fixture
def objects(app, course_people) -> dict[str, int]:
    """A question, a timed test with student1's submitted attempt, a quiz with student1's attempt in progress."""
    from middleware.assessment import attempts, bank
    from middleware.assessment.schemas import parse_exam, parse_question
    from middleware.db import session_factory
    from middleware.models import User

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        tutor, student = session.get(User, course_people["tutor1"]), session.get(User, course_people["student1"])
        course = course_people["course"]
        q = bank.add_question(session, tutor, course, parse_question(QUESTION))
        exam = bank.create_exam(session, tutor, course, parse_exam({
            "title": "T", "kind": "theory", "opens_at": (now - timedelta(hours=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "question_ids": [q.id]}))
        quiz = bank.create_exam(session, tutor, course, parse_exam({"title": "Q", "kind": "quiz",
                                                                    "question_ids": [q.id]}))
        done = attempts.start_attempt(session, student, exam.id, now)
        attempts.submit_attempt(session, student, done.id, now, {str(q.id): "a"})
        open_attempt = attempts.start_attempt(session, student, quiz.id, now)
        session.commit()
        return {"c": course, "q": q.id, "e": exam.id, "z": quiz.id, "a": done.id, "o": open_attempt.id}


@pytest.fixture
def assessment_snapshot(app):
    """Every assessment row as plain tuples."""
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models.assessment import Attempt, AttemptReview, Exam, Question, SurveyResponse

    def take() -> list[object]:
        with session_factory(app)() as session:
            rows: list[object] = []
            for model in (Question, Exam, Attempt, AttemptReview, SurveyResponse):
                for row in session.scalars(select(model).order_by(model.id)):
                    rows.append(tuple(sorted((k, repr(v)) for k, v in vars(row).items() if not k.startswith("_"))))
            return rows

    return take


def _page(client: LabClient, method: str, path: str, form: dict[str, str] | None, logged_in: bool) -> int:
    if method == "GET":
        return client.request("GET", path)[0]
    token = client.csrf_token("/account/password" if logged_in else "/login")
    return client.request(method, path, {**(form or {}), "csrf_token": token})[0]


@pytest.mark.parametrize("who", [None, "student1", "student2", "tutor1", "tutor2", "admin1"])
def test_forbidden_assessment_calls_are_refused_and_change_nothing(client_as, objects, assessment_snapshot,
                                                                   who: str | None) -> None:
    client = client_as(who)
    before = assessment_snapshot()
    checked = 0
    for method, path, allowed, body in PAGES:
        if who in allowed:
            continue
        status = _page(client, method, _fill(path, objects), _fill(body, objects), who is not None)
        assert status == (302 if who is None else 403), f"{who} {method} {path}: {status}"
        checked += 1
    for method, path, allowed, body in APIS:
        if who in allowed:
            continue
        status, answer = api(client, method, _fill(path, objects), _fill(body, objects))
        assert status == (401 if who is None else 403), f"{who} {method} {path}: {status} {answer}"
        checked += 1
    assert checked > 0
    assert assessment_snapshot() == before


def test_a_submitted_attempt_cannot_be_changed_over_http(client_as, objects) -> None:
    student = client_as("student1")
    status, answer = api(student, "POST", f"/api/attempts/{objects['a']}/submit", {"answers": {str(objects['q']): "b"}})
    assert status == 409 and answer["error"]["code"] == "already_submitted"
    status, answer = api(student, "PATCH", f"/api/attempts/{objects['a']}/answers",
                         {"answers": {str(objects['q']): "b"}})
    assert status == 409


def test_quiz_is_corrected_at_once_and_the_tutor_page_and_survey_work(client_as, objects) -> None:
    student = client_as("student1")
    status, answer = api(student, "POST", f"/api/attempts/{objects['o']}/submit", {"answers": {str(objects['q']): "A"}})
    assert status == 200 and answer["attempt"]["score"] == 1 and answer["attempt"]["results"][0]["correct"]
    ratings = {k: 4 for k in ("objectives_clear", "well_presented", "lab_accessible", "corrections_helpful",
                              "system_essential", "system_reliable", "easy_to_use")}
    survey_path = f"/api/courses/{objects['c']}/survey"
    assert api(student, "POST", survey_path, {"ratings": ratings, "comments": "=1+1"})[0] == 201
    assert api(student, "POST", f"/api/courses/{objects['c']}/survey", {"ratings": ratings})[0] == 409
    tutor = client_as("tutor1")
    status, results = api(tutor, "GET", f"/api/courses/{objects['c']}/survey/results")
    # One respondent: the totals would be their answers, so nothing is shown yet.
    assert status == 200 and results["respondents"] == 1 and results["hidden"]
    assert results["questions"] == [] and results["comments"] == []
    for path in (f"/courses/{objects['c']}/assessment", f"/courses/{objects['c']}/survey/results",
                 f"/assessment/exams/{objects['e']}", "/assessment"):
        assert tutor.request("GET", path)[0] == 200, path
    assert student.request("GET", "/assessment")[0] == 200
    status, headers, body = tutor.request("GET", f"/courses/{objects['c']}/grades.csv")
    assert status == 200 and body.startswith("username,") and "student1" in body
