"""A course's survey (the 2003 paper's table 2, or the statements its tutor wrote) and its distribution per
statement."""

from __future__ import annotations

from dataclasses import dataclass

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.assessment.policy import student_course, teaching_course
from middleware.assessment.survey_statements import AGREEMENT, DEFAULT_TITLE, FIXED_STATEMENTS, Statement
from middleware.errors import Refused
from middleware.models import User
from middleware.models.accounts import utc_now
from middleware.models.assessment import CourseSurvey, SurveyResponse


@dataclass(frozen=True)
class ItemDistribution:
    """How many chose each of the five answers to one question."""

    key: str
    label: str
    counts: tuple[int, int, int, int, int]
    low_label: str = AGREEMENT[0]
    high_label: str = AGREEMENT[-1]

    @property
    def total(self) -> int:
        """Answers to the question."""
        return sum(self.counts)

    def percentages(self) -> list[int]:
        """Each answer's share, rounded to whole percent."""
        return [round(100 * c / self.total) if self.total else 0 for c in self.counts]

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"key": self.key, "label": self.label, "counts": list(self.counts), "total": self.total,
                "percentages": self.percentages(), "answers": list(answer_names(self.low_label, self.high_label)),
                "low_label": self.low_label, "high_label": self.high_label}


def answer_names(low_label: str, high_label: str) -> tuple[str, ...]:
    """The five answers' names: the agreement scale's, or "1 (low)", "2", "3", "4", "5 (high)"."""
    if (low_label, high_label) == (AGREEMENT[0], AGREEMENT[-1]):
        return AGREEMENT
    return (f"1 ({low_label})", "2", "3", "4", f"5 ({high_label})")


@dataclass(frozen=True)
class CourseSurveyForm:
    """What a course's students rate: the title and the statements (the tutor's, or the fixed seven)."""

    title: str
    statements: tuple[Statement, ...]
    written: bool  # True: the course's tutor wrote it


def survey_of(session: Session, course_id: int) -> CourseSurveyForm:
    """The course's survey: its tutor's when written, the 2003 paper's seven statements otherwise."""
    row = session.scalar(select(CourseSurvey).where(CourseSurvey.course_id == course_id))
    if row is None:
        return CourseSurveyForm(DEFAULT_TITLE, FIXED_STATEMENTS, False)
    return CourseSurveyForm(row.title, tuple(Statement(**item) for item in row.statements), True)


def respondent_count(session: Session, course_id: int) -> int:
    """How many students have answered the course's survey."""
    return len(session.scalars(select(SurveyResponse.id).where(SurveyResponse.course_id == course_id)).all())


def write_survey(session: Session, actor: User, course_id: int, title: str,
                 statements: list[Statement]) -> CourseSurveyForm:
    """The course's tutor replaces its survey; refused once a student has answered (answers keep their meaning)."""
    teaching_course(session, actor, course_id)
    answered = respondent_count(session, course_id)
    if answered:
        raise Refused(409, "survey_answered", gettext("%(answered)s %(value)s answered this survey, so its "
                                                      "statements stay as they are: their answers are to these.",
                                                      answered=answered,
                                                      value='student has' if answered == 1 else 'students have'),
                      "statements")
    row = session.scalar(select(CourseSurvey).where(CourseSurvey.course_id == course_id))
    if row is None:
        row = CourseSurvey(course_id=course_id)
        session.add(row)
    row.title, row.statements = title, [s.to_dict() for s in statements]
    row.author_id, row.updated_at = actor.id, utc_now()
    session.flush()
    return survey_of(session, course_id)


def has_answered(session: Session, user_id: int, course_id: int) -> bool:
    """True once the student has answered the course's questionnaire."""
    return session.scalar(select(SurveyResponse.id).where(SurveyResponse.course_id == course_id,
                                                          SurveyResponse.user_id == user_id)) is not None


def submit_survey(session: Session, actor: User, course_id: int, ratings: dict[str, int], comments: str) -> None:
    """Stores the student's answers, once per course (a unique constraint, so also across workers)."""
    student_course(session, actor, course_id)
    if has_answered(session, actor.id, course_id):
        raise Refused(409, "already_answered", gettext("You have answered this questionnaire already. Thank you!"))
    session.add(SurveyResponse(course_id=course_id, user_id=actor.id, ratings=ratings, comments=comments))
    try:
        session.flush()
    except IntegrityError:
        raise Refused(409, "already_answered", lazy_gettext("You have answered this questionnaire "
                                                                    "already. Thank you!")) from None


def aggregate(responses: list[dict[str, int]],
              statements: tuple[Statement, ...] = FIXED_STATEMENTS) -> list[ItemDistribution]:
    """The distribution of answers per statement (pure)."""
    out = []
    for statement in statements:
        counts = [0, 0, 0, 0, 0]
        for ratings in responses:
            value = ratings.get(statement.key)
            if isinstance(value, int) and 1 <= value <= 5:
                counts[value - 1] += 1
        out.append(ItemDistribution(statement.key, statement.text, tuple(counts),  # type: ignore[arg-type]
                                    statement.low_label, statement.high_label))
    return out


MIN_RESPONDENTS = 3  # below this, totals and comments could be told apart as one person's


@dataclass(frozen=True)
class SurveyResults:
    """The course's answers; the distribution and comments stay hidden until MIN_RESPONDENTS have answered."""

    respondents: int
    items: list[ItemDistribution]
    comments: list[str]

    @property
    def hidden(self) -> bool:
        """True while too few have answered for the results to stay anonymous."""
        return self.respondents < MIN_RESPONDENTS


def results(session: Session, actor: User, course_id: int) -> SurveyResults:
    """The distribution per question and the free comments (anonymous), for the course's tutors and admins."""
    teaching_course(session, actor, course_id)
    rows = list(session.scalars(select(SurveyResponse).where(SurveyResponse.course_id == course_id)
                                .order_by(SurveyResponse.id)))
    if len(rows) < MIN_RESPONDENTS:
        return SurveyResults(len(rows), [], [])
    return SurveyResults(len(rows), aggregate([r.ratings for r in rows], survey_of(session, course_id).statements),
                         [r.comments for r in rows if r.comments])
