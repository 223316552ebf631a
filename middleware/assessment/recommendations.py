"""Customized learning activities: per-topic results of a student, and activities recommended for weak topics.

Providers are pluggable: each is a function (session, course_id, weak topics, now) -> recommendations, added with
register_provider(). Registered here: the course's open practice quizzes (by their questions' topics), and the
tours and lessons tagged with the topic (their `topics` field; tours and lessons belong to no course).
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
from middleware.models.teaching import Lesson, Tour

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

    kind: str  # practice_quiz, tour, lesson
    title: str
    topic: str
    href: str


Provider = Callable[[Session, int, list[str], datetime], list[Recommendation]]
_PROVIDERS: list[Provider] = []


def register_provider(provider: Provider) -> Provider:
    """Adds a source of recommendations (practice quizzes, tours and lessons here)."""
    _PROVIDERS.append(provider)
    return provider


def topic_scores(session: Session, user_id: int, course_id: int) -> list[TopicScore]:
    """The student's per-topic totals over every submitted attempt in the course (overrides applied)."""
    totals: dict[str, list[float]] = {}
    attempts = session.scalars(select(Attempt).join(Exam, Exam.id == Attempt.exam_id).where(
        Exam.course_id == course_id, Attempt.user_id == user_id, Attempt.status == "submitted"))
    for attempt in list(attempts):
        for result in final_results(attempt, reviews_of(session, attempt.id)):
            if not float(result["max_points"]):  # a rating: an opinion, no measure of a topic
                continue
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


def _tagged(rows: list[Tour] | list[Lesson], kind: str, path: str, topics: list[str]) -> list[Recommendation]:
    out: list[Recommendation] = []
    for row in rows:
        tags = {t.strip() for t in (row.topics or "").split(",")}
        out.extend(Recommendation(kind, row.title, topic, f"/{path}/{row.id}") for topic in topics if topic in tags)
    return out


@register_provider
def tours(session: Session, course_id: int, topics: list[str], now: datetime) -> list[Recommendation]:
    """Tours tagged with a weak topic."""
    return _tagged(list(session.scalars(select(Tour).where(Tour.topics != "").order_by(Tour.title, Tour.id))),
                   "tour", "tours", topics)


@register_provider
def lessons(session: Session, course_id: int, topics: list[str], now: datetime) -> list[Recommendation]:
    """Video lessons tagged with a weak topic."""
    return _tagged(list(session.scalars(select(Lesson).where(Lesson.topics != "").order_by(Lesson.title, Lesson.id))),
                   "lesson", "lessons", topics)


def recommend(session: Session, user_id: int, course_id: int, now: datetime) -> list[Recommendation]:
    """Activities for the student's weak topics in the course from every provider, weakest topic first."""
    topics = weak_topics(topic_scores(session, user_id, course_id))
    found = [r for provider in _PROVIDERS for r in provider(session, course_id, topics, now)] if topics else []
    return sorted(found, key=lambda r: topics.index(r.topic) if r.topic in topics else len(topics))
