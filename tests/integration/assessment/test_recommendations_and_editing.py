"""Tours and lessons recommended by topic; the tutor's page edits and deletes questions and tests, and writes the
task of every experimental kind. Services on a migrated database, then the pages and API over HTTP."""

from __future__ import annotations

import re
from datetime import UTC, datetime, timedelta
from html import unescape

import pytest

from middleware.assessment import attempts, bank, recommendations
from middleware.assessment.schemas import parse_exam
from middleware.models.assessment import Exam, Question
from middleware.teaching.cues import parse_cue_track
from middleware.teaching.lessons import LessonDraft, LessonInvalid, check_lesson, save_lesson
from middleware.teaching.tours import TourInvalid, save_tour
from tests.conftest import LabClient
from tests.integration.assessment.test_attempt_rules import T0, _timed, world  # noqa: F401
from tests.integration.bookings.conftest import api

STEP = {"text": "Look.", "panel": "camera", "condition": {"type": "manual"}}
CUES = "WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{\"stop\": true}\n"


def _tour(session, title: str, topics: object):
    return save_tour(session, {"title": title, "topics": topics, "steps": [STEP]}, None, None)


def _lesson(session, title: str, topics: str):
    cues, errors = parse_cue_track(CUES, None)
    assert not errors
    slug = re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")
    return save_lesson(session, LessonDraft(slug, title, "", "v.webm", cues, topics), None)


def test_a_student_weak_in_a_topic_gets_its_quiz_tour_and_lesson_and_not_the_others(world) -> None:  # noqa: F811
    session, people, course, questions = world
    odometry_q, sensors_q = questions
    sensors_quiz = bank.create_exam(session, people["t1"], course.id, parse_exam(
        {"title": "Sensors practice", "kind": "quiz", "question_ids": [sensors_q.id]}))
    bank.create_exam(session, people["t1"], course.id, parse_exam(
        {"title": "Odometry practice", "kind": "quiz", "question_ids": [odometry_q.id]}))
    sensors_tour = _tour(session, "Sonar ring", "Sensors,  SONAR, sensors")
    _tour(session, "Wheels", "odometry")
    _tour(session, "Untagged", None)
    sensors_lesson = _lesson(session, "Laser lesson", "laser, sensors")
    _lesson(session, "Odometry lesson", "odometry")
    exam = _timed(session, people["t1"], course, questions)
    attempt = attempts.start_attempt(session, people["s1"], exam.id, T0)
    attempts.submit_attempt(session, people["s1"], attempt.id, T0 + timedelta(seconds=5),
                            {str(odometry_q.id): 1, str(sensors_q.id): {"value": "9", "unit": "m"}})
    session.commit()
    assert sensors_tour.topics == "sensors, sonar"  # normalised: lower case, sorted, no repeats
    recs = recommendations.recommend(session, people["s1"].id, course.id, T0)
    assert [(r.kind, r.topic, r.title, r.href) for r in recs] == [
        ("practice_quiz", "sensors", "Sensors practice", f"/assessment/exams/{sensors_quiz.id}"),
        ("tour", "sensors", "Sonar ring", f"/tours/{sensors_tour.id}"),
        ("lesson", "sensors", "Laser lesson", f"/lessons/{sensors_lesson.id}"),
    ]
    assert recommendations.recommend(session, people["s2"].id, course.id, T0) == []  # no results, no advice


def test_topics_are_checked_on_tours_and_lessons() -> None:
    with pytest.raises(TourInvalid) as tour:
        save_tour(None, {"title": "T", "topics": ",".join(f"t{i}" for i in range(11)), "steps": [STEP]},
                  None, None)
    assert tour.value.field == "topics"
    with pytest.raises(LessonInvalid) as lesson:
        check_lesson({"title": "L", "video_name": "v.webm", "cues": CUES, "topics": 5}, {}, ["v.webm"])
    assert lesson.value.errors[0].field == "topics"
    draft = check_lesson({"title": "L", "video_name": "v.webm", "cues": CUES, "topics": " Laser , laser,odometry"},
                         {}, ["v.webm"])
    assert draft.topics == "laser, odometry"


# --- the tutor's page over HTTP --------------------------------------------------------------------------------


@pytest.fixture
def bank_objects(app, course_people) -> dict[str, int]:
    """Two questions; a quiz using both; a timed test with student1's submitted attempt; an unattempted test."""
    from middleware.assessment.schemas import parse_question
    from middleware.db import session_factory
    from middleware.models import User

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        tutor, student = session.get(User, course_people["tutor1"]), session.get(User, course_people["student1"])
        course = course_people["course"]
        q1 = bank.add_question(session, tutor, course, parse_question(
            {"kind": "single", "prompt": "Odometry <drifts>?", "choices": ["no", "yes"], "correct": 1,
             "topics": ["odometry"]}))
        q2 = bank.add_question(session, tutor, course, parse_question(
            {"kind": "text", "prompt": "Sensor?", "accepted": ["sonar"], "case_sensitive": True}))
        quiz = bank.create_exam(session, tutor, course, parse_exam(
            {"title": "Quiz", "kind": "quiz", "question_ids": [q2.id, q1.id]}))
        timed = bank.create_exam(session, tutor, course, parse_exam({
            "title": "Midterm", "kind": "experimental", "opens_at": (now - timedelta(hours=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1, seconds=30)).isoformat(), "duration_s": 600,
            "question_ids": [q2.id, q1.id], "task_kind": "wall_following", "x1_m": 0, "y1_m": 0, "x2_m": 2,
            "y2_m": 0, "distance_m": 0.3, "task_topics": "walls", "rubric": "0.05:1, 0.1:0.3"}))
        done = attempts.start_attempt(session, student, timed.id, now, lambda robot, user: True)
        attempts.submit_attempt(session, student, done.id, now, {str(q1.id): 1})
        session.commit()
        return {"c": course, "q1": q1.id, "q2": q2.id, "quiz": quiz.id, "timed": timed.id}


def _post(client: LabClient, path: str, pairs: list[tuple[str, str]]) -> tuple[int, str]:
    token = client.csrf_token("/account/password")
    status, _, body = client.request("POST", path, [*pairs, ("csrf_token", token)])
    return status, body


def _rows(app, model, **where):
    from sqlalchemy import select

    from middleware.db import session_factory

    with session_factory(app)() as session:
        return list(session.scalars(select(model).filter_by(**where).order_by(model.id)))


def _form_fields(body: str, form_id: str) -> list[tuple[str, str]]:
    """What a browser would send from the form: text inputs, checked boxes, selected options, textareas."""
    form = body[body.index(f'id="{form_id}"'):]
    form = form[:form.index("</form>")]
    pairs = []
    for tag in re.findall(r"<input [^>]*>", form):
        name, value = re.search(r'name="([^"]+)"', tag), re.search(r'value="([^"]*)"', tag)
        if name and ('type="checkbox"' not in tag or " checked" in tag):
            pairs.append((name.group(1), unescape(value.group(1)) if value else ""))
    for name, options in re.findall(r'<select id="[^"]+" name="([^"]+)"[^>]*>(.*?)</select>', form, re.S):
        chosen = re.search(r'<option value="([^"]*)" selected', options)
        pairs.append((name, chosen.group(1) if chosen else ""))
    pairs += [(n, unescape(v)) for n, v in re.findall(r'<textarea [^>]*name="([^"]+)"[^>]*>(.*?)</textarea>', form,
                                                      re.S)]
    return pairs


def test_the_tutor_edits_and_deletes_questions_from_the_page(app, client_as, bank_objects) -> None:
    tutor, c, q1 = client_as("tutor1"), bank_objects["c"], bank_objects["q1"]
    status, _, body = tutor.request("GET", f"/courses/{c}/assessment?question={q1}")
    assert status == 200 and f"Edit question #{q1}" in body and "Odometry &lt;drifts&gt;?" in body
    fields = _form_fields(body, "question-form")
    # The page numbers choices from 1: "yes", the second line, is choice 2 (stored as index 1).
    assert ("choices", "no\nyes") in fields and ("correct", "2") in fields and ("topics", "odometry") in fields
    assert ("tolerance", "") in fields and ("value", "") in fields
    edited = [(k, v) for k, v in fields if k not in ("csrf_token", "prompt", "points")]
    status, _ = _post(tutor, f"/courses/{c}/assessment/questions/{q1}",
                      [*edited, ("prompt", "Does odometry drift?"), ("points", "2")])
    assert status == 303
    question = _rows(app, Question, id=q1)[0]
    assert (question.prompt, question.points, question.spec["correct"]) == ("Does odometry drift?", 2.0, 1)
    # The text question's form round-trips, case sensitivity included.
    q2 = bank_objects["q2"]
    fields = _form_fields(tutor.request("GET", f"/courses/{c}/assessment?question={q2}")[2], "question-form")
    assert ("case_sensitive", "1") in fields
    assert _post(tutor, f"/courses/{c}/assessment/questions/{q2}", [(k, v) for k, v in fields
                                                                      if k != "csrf_token"])[0] == 303
    assert _rows(app, Question, id=q2)[0].spec == {"accepted": ["sonar"], "case_sensitive": True}
    # An invalid edit is refused with the field named, and the form keeps what was typed.
    status, body = _post(tutor, f"/courses/{c}/assessment/questions/{q1}",
                         [("kind", "single"), ("prompt", "Kept <text>"), ("choices", "a\nb"), ("correct", "7")])
    assert status == 400 and "correct:" in body and "Kept &lt;text&gt;" in body and f"Edit question #{q1}" in body
    # Deleting: gone from the bank and from the unattempted quiz; the attempted test keeps its list and marks.
    assert _post(tutor, f"/courses/{c}/assessment/questions/{q1}/delete", [])[0] == 303
    assert _rows(app, Question, id=q1) == []
    assert _rows(app, Exam, id=bank_objects["quiz"])[0].question_ids == [q2]
    assert _rows(app, Exam, id=bank_objects["timed"])[0].question_ids == [q2, q1]
    # Another course's tutor and an unknown question.
    assert _post(client_as("tutor2"), f"/courses/{c}/assessment/questions/{q2}/delete", [])[0] == 403
    assert tutor.request("GET", f"/courses/{c}/assessment?question=99999")[0] == 404
    assert _post(tutor, f"/courses/{bank_objects['c']}/assessment/questions/99999", [("kind", "text")])[0] == 404


def test_the_tutor_edits_tests_and_cannot_delete_one_with_attempts(app, client_as, bank_objects) -> None:
    tutor, c, timed = client_as("tutor1"), bank_objects["c"], bank_objects["timed"]
    status, _, body = tutor.request("GET", f"/courses/{c}/assessment?exam={timed}")
    assert status == 200 and 'id="exam-frozen"' in body
    fields = _form_fields(body, "exam-form")
    assert ("task_kind", "wall_following") in fields and ("distance_m", "0.3") in fields
    # The prefilled form sends back the same questions (in the stored order) and task: only the title changes.
    sent = [(k, v) for k, v in fields if k not in ("csrf_token", "title")] + [("title", "Midterm (room B)")]
    assert _post(tutor, f"/courses/{c}/assessment/exams/{timed}", sent)[0] == 303
    exam = _rows(app, Exam, id=timed)[0]
    assert exam.title == "Midterm (room B)" and exam.question_ids == [bank_objects["q2"], bank_objects["q1"]]
    assert exam.task["rubric"] == [[0.05, 1.0], [0.1, 0.3]] and exam.task["topics"] == ["walls"]
    # Changing the task of a started test is refused with the reason.
    changed = [(k, "0.5" if k == "distance_m" else v) for k, v in sent]
    status, body = _post(tutor, f"/courses/{c}/assessment/exams/{timed}", changed)
    assert status == 409 and "only its title and times can change" in body
    # Deleting a test with attempts: refused, clearly; over the API too.
    status, body = _post(tutor, f"/courses/{c}/assessment/exams/{timed}/delete", [])
    assert status == 409 and "has attempts, so it cannot be deleted" in unescape(body)
    status, answer = api(tutor, "DELETE", f"/api/exams/{timed}")
    assert status == 409 and answer["error"]["code"] == "exam_has_attempts"
    assert _rows(app, Exam, id=timed)
    # A quiz nobody started is edited freely and deleted.
    quiz = bank_objects["quiz"]
    fields = _form_fields(tutor.request("GET", f"/courses/{c}/assessment?exam={quiz}")[2], "exam-form")
    sent = [(k, v) for k, v in fields if k not in ("csrf_token", "question_ids")] + [("question_ids",
                                                                                      str(bank_objects["q1"]))]
    assert _post(tutor, f"/courses/{c}/assessment/exams/{quiz}", sent)[0] == 303
    assert _rows(app, Exam, id=quiz)[0].question_ids == [bank_objects["q1"]]
    assert api(client_as("tutor2"), "DELETE", f"/api/exams/{quiz}")[0] == 403
    assert _post(tutor, f"/courses/{c}/assessment/exams/{quiz}/delete", [])[0] == 303
    assert _rows(app, Exam, id=quiz) == []


@pytest.mark.parametrize(("task_kind", "extra", "expected"), [
    ("reach_point", [("x_m", "1.5"), ("y_m", "-0.5")], {"x_m": 1.5, "y_m": -0.5}),
    ("wall_following", [("x1_m", "0"), ("y1_m", "1"), ("x2_m", "3"), ("y2_m", "1"), ("distance_m", "0.4"),
                        ("min_travel_m", "2")],
     {"x1_m": 0.0, "y1_m": 1.0, "x2_m": 3.0, "y2_m": 1.0, "distance_m": 0.4, "min_travel_m": 2.0}),
    ("report_pose", [], {}),
])
def test_the_page_writes_every_experimental_task_kind(app, client_as, bank_objects, task_kind: str,
                                                      extra: list[tuple[str, str]], expected: dict) -> None:
    tutor, c = client_as("tutor1"), bank_objects["c"]
    assert f'data-task-kind="{task_kind}"' in tutor.request("GET", f"/courses/{c}/assessment")[2]
    now = datetime.now(UTC)
    status, _ = _post(tutor, f"/courses/{c}/assessment/exams", [
        ("title", f"Lab {task_kind}"), ("kind", "experimental"), ("opens_at", now.strftime("%Y-%m-%dT%H:%M")),
        ("closes_at", (now + timedelta(days=1)).strftime("%Y-%m-%dT%H:%M")), ("duration_s", "300"),
        ("task_kind", task_kind), ("rubric", "0.1:1, 0.3:0.5"), ("task_points", "8"), ("task_topics", "Lab"),
        ("robot_name", "lab-1"), ("instructions", "Go."), *extra])
    assert status == 303
    task = _rows(app, Exam, title=f"Lab {task_kind}")[0].task
    assert task == {"kind": task_kind, "rubric": [[0.1, 1.0], [0.3, 0.5]], "points": 8.0, "topics": ["lab"],
                    "instructions": "Go.", **expected}


def test_the_students_page_lists_the_recommended_tour(app, client_as, bank_objects) -> None:
    from middleware.db import session_factory

    with session_factory(app)() as session:  # student1's experimental task scored 0 (nothing recorded): "walls"
        tour_id = _tour(session, "Walls <and> sonars", "Walls").id
        other_id = _tour(session, "Wheels", "odometry").id
        session.commit()
    student = client_as("student1")
    status, _, body = student.request("GET", "/assessment")
    assert status == 200 and f'href="/tours/{tour_id}"' in body and "Walls &lt;and&gt; sonars" in body
    assert f'href="/tours/{other_id}"' not in body
    status, answer = api(student, "GET", f"/api/courses/{bank_objects['c']}/recommendations")
    assert status == 200 and [(r["kind"], r["topic"], r["href"]) for r in answer["recommendations"]] == [
        ("tour", "walls", f"/tours/{tour_id}")]
    assert f'href="/tours/{tour_id}"' not in client_as("student2").request("GET", "/assessment")[2]
