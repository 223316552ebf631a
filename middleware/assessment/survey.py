"""The system evaluation questionnaire (the 2003 paper's table 2) and its distribution per question."""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.assessment.policy import student_course, teaching_course
from middleware.assessment.schemas import AGREEMENT, SURVEY_ITEMS
from middleware.errors import Refused
from middleware.models import User
from middleware.models.assessment import SurveyResponse


@dataclass(frozen=True)
class ItemDistribution:
    """How many chose each of the five answers to one question."""

    key: str
    label: str
    counts: tuple[int, int, int, int, int]

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
                "percentages": self.percentages(), "answers": list(AGREEMENT)}


def has_answered(session: Session, user_id: int, course_id: int) -> bool:
    """True once the student has answered the course's questionnaire."""
    return session.scalar(select(SurveyResponse.id).where(SurveyResponse.course_id == course_id,
                                                          SurveyResponse.user_id == user_id)) is not None


def submit_survey(session: Session, actor: User, course_id: int, ratings: dict[str, int], comments: str) -> None:
    """Stores the student's answers, once per course (a unique constraint, so also across workers)."""
    student_course(session, actor, course_id)
    if has_answered(session, actor.id, course_id):
        raise Refused(409, "already_answered", "You have answered this questionnaire already. Thank you!")
    session.add(SurveyResponse(course_id=course_id, user_id=actor.id, ratings=ratings, comments=comments))
    try:
        session.flush()
    except IntegrityError:
        raise Refused(409, "already_answered", "You have answered this questionnaire already. Thank you!") from None


def aggregate(responses: list[dict[str, int]]) -> list[ItemDistribution]:
    """The distribution of answers per question (pure)."""
    out = []
    for key, label in SURVEY_ITEMS:
        counts = [0, 0, 0, 0, 0]
        for ratings in responses:
            value = ratings.get(key)
            if isinstance(value, int) and 1 <= value <= 5:
                counts[value - 1] += 1
        out.append(ItemDistribution(key, label, tuple(counts)))  # type: ignore[arg-type]
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
    return SurveyResults(len(rows), aggregate([r.ratings for r in rows]), [r.comments for r in rows if r.comments])
