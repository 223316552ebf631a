"""Customized learning activities: per-topic results of a student, and activities recommended for weak topics.

Providers are pluggable: each is a function (session, course_id, weak topics, now) -> recommendations. This
package registers practice quizzes; tours and lessons do not exist yet, and will register their own provider
with register_provider() when they do.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.assessment.attempts import window_state
from middleware.assessment.bank import list_exams, questions_of
from middleware.assessment.review import final_results, reviews_of
from middleware.models.assessment import Attempt, Exam

WEAK_BELOW = 0.6  # a topic is weak when the student scored less than 60% of its points


@dataclass(frozen=True)
class TopicScore:
    """A student's points on one topic over their submitted attempts."""

    topic: str
    points: float
    max_points: float

    @property
    def ratio(self) -> float:
        """Points over the maximum (0-1)."""
        return self.points / self.max_points if self.max_points else 0.0


@dataclass(frozen=True)
class Recommendation:
    """One activity to do for a weak topic."""

    kind: str  # practice_quiz (tour, lesson: later)
    title: str
    topic: str
    href: str


Provider = Callable[[Session, int, list[str], datetime], list[Recommendation]]
_PROVIDERS: list[Provider] = []


def register_provider(provider: Provider) -> Provider:
    """Adds a source of recommendations (practice quizzes here; tours and lessons when they exist)."""
    _PROVIDERS.append(provider)
    return provider


def topic_scores(session: Session, user_id: int, course_id: int) -> list[TopicScore]:
    """The student's per-topic totals over every submitted attempt in the course (overrides applied)."""
    totals: dict[str, list[float]] = {}
    attempts = session.scalars(select(Attempt).join(Exam, Exam.id == Attempt.exam_id).where(
        Exam.course_id == course_id, Attempt.user_id == user_id, Attempt.status == "submitted"))
    for attempt in list(attempts):
        for result in final_results(attempt, reviews_of(session, attempt.id)):
            for topic in result.get("topics") or []:
                pair = totals.setdefault(topic, [0.0, 0.0])
                pair[0] += float(result["points"])
                pair[1] += float(result["max_points"])
    return [TopicScore(t, round(p, 4), round(m, 4)) for t, (p, m) in sorted(totals.items())]


def weak_topics(scores: list[TopicScore]) -> list[str]:
    """The topics under WEAK_BELOW, weakest first."""
    return [s.topic for s in sorted(scores, key=lambda s: (s.ratio, s.topic)) if s.ratio < WEAK_BELOW]


@register_provider
def practice_quizzes(session: Session, course_id: int, topics: list[str], now: datetime) -> list[Recommendation]:
    """Open quizzes of the course with questions on the weak topics."""
    out = []
    for exam in list_exams(session, course_id):
        if exam.kind != "quiz" or window_state(exam, now) != "open":
            continue
        covered = {t for q in questions_of(session, exam) for t in q.topics}
        for topic in topics:
            if topic in covered:
                out.append(Recommendation("practice_quiz", exam.title, topic, f"/assessment/exams/{exam.id}"))
    return out


def recommend(session: Session, user_id: int, course_id: int, now: datetime) -> list[Recommendation]:
    """Activities for the student's weak topics in the course, from every provider."""
    topics = weak_topics(topic_scores(session, user_id, course_id))
    return [r for provider in _PROVIDERS for r in provider(session, course_id, topics, now)] if topics else []
