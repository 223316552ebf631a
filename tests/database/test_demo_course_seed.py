"""The demo course seeds once on SQLite and PostgreSQL alike (the seed runs through the services, in one
transaction); a second run adds nothing."""

from __future__ import annotations

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from middleware.auth.services import create_user
from middleware.db import make_engine
from middleware.demo_course import DEMO_QUESTIONS, DEMO_SURVEY_ANSWERS, seed_demo_course
from middleware.models import Course, CourseMembership
from middleware.models.assessment import Exam, Question
from tests.conftest import migrate_to_head


def test_the_demo_course_seeds_once(database_url: str) -> None:
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    try:
        with Session(engine) as session:
            create_user(session, "tutor", "tutor", "a-long-enough-password")
            create_user(session, "student", "student", "a-long-enough-password")
            first = seed_demo_course(session)
            session.commit()
        with Session(engine) as session:
            again = seed_demo_course(session)
            session.commit()
            counts = [session.scalar(select(func.count()).select_from(t))
                      for t in (Course, CourseMembership, Question, Exam)]
        assert first.added and again.added == [] and again.course_id == first.course_id
        assert counts == [1, 2 + len(DEMO_SURVEY_ANSWERS), len(DEMO_QUESTIONS), 5]  # the tutor, the student, classmates
    finally:
        engine.dispose()


def test_the_spanish_demo_course_seeds_once(database_url: str) -> None:
    from middleware.demo_course import DEMO_QUESTIONS_ES, DEMO_SURVEY_ANSWERS_ES, seed_spanish_demo_course
    from middleware.models.assessment import SurveyResponse

    migrate_to_head(database_url)
    engine = make_engine(database_url)
    try:
        with Session(engine) as session:
            create_user(session, "tutor", "tutor", "a-long-enough-password")
            create_user(session, "student", "student", "a-long-enough-password")
            first = seed_spanish_demo_course(session)
            session.commit()
        with Session(engine) as session:
            again = seed_spanish_demo_course(session)
            session.commit()
            counts = [session.scalar(select(func.count()).select_from(t))
                      for t in (Course, CourseMembership, Question, Exam, SurveyResponse)]
        assert first.added and again.added == [] and again.course_id == first.course_id
        assert counts == [1, 2 + len(DEMO_SURVEY_ANSWERS_ES), len(DEMO_QUESTIONS_ES), 5, len(DEMO_SURVEY_ANSWERS_ES)]
    finally:
        engine.dispose()
