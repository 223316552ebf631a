"""The demo content exists in both languages (issue 29): `telelab up` seeds, in English and in Spanish, a tour, a
lesson with its tests before and after, a course's quiz, timed and experimental tests, and a survey whose charts
show; the Spanish ones are written in Spanish, with the same questions and grading; a second start adds nothing."""

from __future__ import annotations

import json
import re

from sqlalchemy import func, select

# Words only English writes; each Spanish text of the demo must hold none of them.
ENGLISH = re.compile(r"\b(the|and|of|to|with|your|is|are|which|what|how|helped|learn|test|quiz|lesson|survey)\b",
                     re.IGNORECASE)
GRADING = ("kind", "correct", "value", "tolerance", "unit")  # what grades a question, beside its words


def _seed(app) -> list[str]:
    from middleware.lab_runner import seed_demo_content
    from middleware.teaching.demo_content import DEMO_VIDEO
    from middleware.teaching.lessons import video_dir

    with app.app_context():  # the demo lessons are added once their video exists (recording it is slow)
        videos = video_dir(app.instance_path)
    videos.mkdir(parents=True, exist_ok=True)
    (videos / DEMO_VIDEO).write_bytes(b"\x1a\x45\xdf\xa3")
    return seed_demo_content(app, record_video=False)  # all `telelab up` seeds, in its order


def _content(session, course_code: str, tour_slug: str, lesson_slug: str) -> dict[str, object]:
    """Each kind of demo content of one language, as its texts."""
    from middleware.assessment import survey
    from middleware.auth.services import find_user
    from middleware.models import Course
    from middleware.models.assessment import Exam, Question
    from middleware.models.teaching import Lesson, Tour

    course_id = session.scalar(select(Course.id).where(Course.code == course_code))
    tour = session.scalar(select(Tour).where(Tour.slug == tour_slug))
    lesson = session.scalar(select(Lesson).where(Lesson.slug == lesson_slug))
    exams: dict[str, Exam] = {}  # each kind's first: the practice quiz before the lesson's quizzes
    for exam in session.scalars(select(Exam).where(Exam.course_id == course_id).order_by(Exam.id)):
        exams.setdefault(exam.kind, exam)
    lesson_tests = [session.get(Exam, exam_id) for exam_id in (lesson.before_exam_id, lesson.after_exam_id)]
    form = survey.survey_of(session, course_id)
    results = survey.results(session, find_user(session, "tutor"), course_id)
    return {
        "tour": [tour.title, tour.summary, *(step["text"] for step in json.loads(tour.steps_json))],
        "lesson": [lesson.title, lesson.summary],
        "lesson tests": lesson_tests,
        "tests": exams,
        "survey": form,
        "survey results": results,
        "questions": list(session.scalars(select(Question).where(Question.course_id == course_id)
                                          .order_by(Question.id))),
        "course id": course_id,
    }


def test_every_kind_of_demo_content_exists_in_english_and_in_spanish(app, demo_accounts) -> None:
    from middleware.assessment import survey
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.demo_course import (
        DEMO_COURSE_CODE,
        DEMO_COURSE_ES_CODE,
        DEMO_QUESTIONS,
        DEMO_QUESTIONS_ES,
        DEMO_SURVEY_ANSWERS_ES,
    )
    from middleware.models import Course, CourseMembership
    from middleware.models.assessment import Exam, Question, SurveyResponse
    from middleware.models.teaching import Lesson, Tour

    added = _seed(app)
    assert "lesson primeros-movimientos" in added and "tour control-directo" in added
    with session_factory(app)() as session:
        english = _content(session, DEMO_COURSE_CODE, "direct-control", "first-moves")
        spanish = _content(session, DEMO_COURSE_ES_CODE, "control-directo", "primeros-movimientos")
        for language in (english, spanish):
            assert all(test is not None and test.course_id == language["course id"] and test.kind == "quiz"
                       for test in language["lesson tests"])  # the lesson's tests, of its language's course
            assert {"quiz", "theory", "experimental"} <= set(language["tests"])
            assert language["survey"].written and len(language["survey"].statements) == 8
            results = language["survey results"]  # the tutor's charts show: enough answers
            assert results.respondents == survey.MIN_RESPONDENTS and not results.hidden
            student = find_user(session, "student")
            assert session.scalar(select(CourseMembership.id).where(  # the demo student finds it on their pages
                CourseMembership.course_id == language["course id"], CourseMembership.user_id == student.id))

        # The Spanish ones are Spanish: a few of their words, and no English word in any of their texts.
        assert spanish["tour"][0] == "Control directo" and "Abre la consola" in spanish["tour"][-1]
        assert spanish["lesson"][0] == "Primeros movimientos" and "Si pausas, el robot se para" in spanish["lesson"][1]
        assert [t.title for t in spanish["lesson tests"]] == ["Antes de la lección: primeros movimientos",
                                                            "Después de la lección: primeros movimientos"]
        assert spanish["tests"]["quiz"].title.startswith("Cuestionario de práctica")
        assert spanish["tests"]["theory"].title.startswith("Prueba cronometrada")
        assert "baldosa naranja" in spanish["tests"]["experimental"].task["instructions"]
        assert spanish["survey"].title == "Evalúa el laboratorio"
        assert spanish["survey"].statements[5].text == "El sistema era fiable"
        texts = [*spanish["tour"], *spanish["lesson"], *(t.title for t in spanish["lesson tests"]),
                 *(t.title for t in spanish["tests"].values()), spanish["tests"]["experimental"].task["instructions"],
                 spanish["survey"].title, *(s.text for s in spanish["survey"].statements),
                 *(end for s in spanish["survey"].statements for end in (s.low_label, s.high_label)),
                 *(q.prompt for q in spanish["questions"]),
                 *session.scalars(select(SurveyResponse.comments).where(
                     SurveyResponse.course_id == spanish["course id"]))]
        assert [text for text in texts if ENGLISH.search(text)] == []
        assert sum("¿" in q.prompt for q in spanish["questions"]) >= 5

        # The same questions and the same grading: each Spanish question marks as its English one.
        assert len(spanish["questions"]) == len(english["questions"]) == len(DEMO_QUESTIONS_ES) == len(DEMO_QUESTIONS)
        for english_q, spanish_q in zip(DEMO_QUESTIONS, DEMO_QUESTIONS_ES, strict=True):
            assert {k: english_q.get(k) for k in GRADING} == {k: spanish_q.get(k) for k in GRADING}
            assert len(english_q.get("choices", [])) == len(spanish_q.get("choices", []))
        for kind in ("quiz", "theory", "experimental"):
            english_test, spanish_test = english["tests"][kind], spanish["tests"][kind]
            assert (english_test.duration_s, english_test.max_attempts) == (spanish_test.duration_s,
                                                                             spanish_test.max_attempts)
            assert len(english_test.question_ids) == len(spanish_test.question_ids)
        english_task, spanish_task = (  # the experimental task's target and rubric, beside its words
            {k: v for k, v in test.task.items() if k not in ("instructions", "topics")}
            for test in (english["tests"]["experimental"], spanish["tests"]["experimental"]))
        assert english_task == spanish_task
        assert not any(find_user(session, name).is_active for name in DEMO_SURVEY_ANSWERS_ES)
        counts = [session.scalar(select(func.count()).select_from(t))
                  for t in (Course, CourseMembership, Question, Exam, Tour, Lesson, SurveyResponse)]

    # A second `telelab up` adds nothing in either language.
    assert _seed(app) == []
    with session_factory(app)() as session:
        assert counts == [session.scalar(select(func.count()).select_from(t))
                          for t in (Course, CourseMembership, Question, Exam, Tour, Lesson, SurveyResponse)]
