"""A lesson's test before and after (the 2022 paper's comprehension test, with a 1-5 rating per part), and the
comparison of the two per part.

A part is a topic of the tests' questions ("part 1: driving"): a question counts for each of its topics. Marked
questions give the share of points before and after; rating questions (0 of 0 points) give the mean rating. Only
submitted attempts count: a student's first one of the test before, and their last one of the test after.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import Refused
from middleware.models import Role, User
from middleware.models.assessment import Attempt, AttemptReview, Exam
from middleware.models.teaching import Lesson

WHOLE_TEST = "the whole test"


@dataclass
class PartTotals:
    """Points and ratings of one part, summed over attempts."""

    points: float = 0.0
    max_points: float = 0.0
    ratings: list[int] = field(default_factory=list)


@dataclass(frozen=True)
class PartComparison:
    """One part before and after: shares of the points (0-1, None without marked questions) and mean ratings."""

    part: str
    before: float | None
    after: float | None
    rating_before: float | None
    rating_after: float | None

    @property
    def change(self) -> float | None:
        """after - before, when both were measured."""
        return None if self.before is None or self.after is None else round(self.after - self.before, 4)

    def to_dict(self) -> dict[str, Any]:
        """The JSON form."""
        return {"part": self.part, "before": self.before, "after": self.after, "change": self.change,
                "rating_before": self.rating_before, "rating_after": self.rating_after}


def with_overrides(results: list[dict[str, Any]], reviews: Iterable[AttemptReview]) -> list[dict[str, Any]]:
    """The attempt's results with each item's latest mark set by a tutor."""
    latest = {r.item: r.points for r in sorted(reviews, key=lambda r: r.id) if r.points is not None and r.item}
    return [{**r, "points": latest.get(r["item"], r["points"])} for r in results]


def part_totals(attempts: Iterable[tuple[list[dict[str, Any]], dict[str, Any]]]) -> dict[str, PartTotals]:
    """Per part (and WHOLE_TEST), the marked points and the ratings of (results, answers) pairs (pure)."""
    totals: dict[str, PartTotals] = {}
    for results, answers in attempts:
        for result in results:
            parts = [WHOLE_TEST, *(result.get("topics") or [])]
            rating = answers.get(str(result["item"])) if not float(result["max_points"]) else None
            for part in parts:
                total = totals.setdefault(part, PartTotals())
                if float(result["max_points"]):
                    total.points += float(result["points"])
                    total.max_points += float(result["max_points"])
                elif isinstance(rating, int) and part != WHOLE_TEST:
                    total.ratings.append(rating)
    return totals


def compare_parts(before: dict[str, PartTotals], after: dict[str, PartTotals]) -> list[PartComparison]:
    """Each part of either test, before against after (pure); the whole test last."""
    def share(totals: PartTotals | None) -> float | None:
        return round(totals.points / totals.max_points, 4) if totals and totals.max_points else None

    def mean(totals: PartTotals | None) -> float | None:
        return round(sum(totals.ratings) / len(totals.ratings), 2) if totals and totals.ratings else None

    parts = sorted((set(before) | set(after)) - {WHOLE_TEST}) + [WHOLE_TEST]
    rows = [PartComparison(p, share(before.get(p)), share(after.get(p)), mean(before.get(p)), mean(after.get(p)))
            for p in parts]
    return [r for r in rows if (r.before, r.after, r.rating_before, r.rating_after) != (None, None, None, None)]


def _submitted(session: Session, exam_id: int | None, user_ids: set[int] | None, last: bool) -> dict[int, Attempt]:
    """Each student's first (or last) submitted attempt at the exam."""
    if exam_id is None:
        return {}
    query = select(Attempt).where(Attempt.exam_id == exam_id, Attempt.status == "submitted")
    if user_ids is not None:
        query = query.where(Attempt.user_id.in_(user_ids))
    chosen: dict[int, Attempt] = {}
    for attempt in session.scalars(query.order_by(Attempt.submitted_at, Attempt.id)):
        if last or attempt.user_id not in chosen:
            chosen[attempt.user_id] = attempt
    return chosen


def _pairs(session: Session, attempts: Iterable[Attempt]) -> list[tuple[list[dict[str, Any]], dict[str, Any]]]:
    out = []
    for attempt in attempts:
        reviews = session.scalars(select(AttemptReview).where(AttemptReview.attempt_id == attempt.id))
        out.append((with_overrides(attempt.results or [], reviews), attempt.answers or {}))
    return out


@dataclass(frozen=True)
class LessonResults:
    """The comparison per part, and how many students took both tests (one: the student's own)."""

    parts: list[PartComparison]
    students: int
    whose: str  # "yours" or "class"


def lesson_results(session: Session, lesson: Lesson, actor: User) -> LessonResults:
    """A student's own before/after per part; the class's (students who took both) for the tests' tutors."""
    if lesson.before_exam_id is None or lesson.after_exam_id is None:
        raise Refused(404, "no_tests", gettext("This lesson has no test before and after to compare."), "lesson_id")
    exam = session.get(Exam, lesson.after_exam_id)
    class_view = actor.role != Role.STUDENT and exam is not None and teaches_course(session, actor, exam.course_id)
    users = None if class_view else {actor.id}
    before = _submitted(session, lesson.before_exam_id, users, last=False)
    after = _submitted(session, lesson.after_exam_id, users, last=True)
    both = sorted(set(before) & set(after))
    parts = compare_parts(part_totals(_pairs(session, (before[u] for u in both))),
                          part_totals(_pairs(session, (after[u] for u in both))))
    return LessonResults(parts, len(both), "class" if class_view else "yours")


@dataclass(frozen=True)
class LessonGate:
    """Where a learner stands with the lesson's tests."""

    before_exam: Exam | None
    after_exam: Exam | None
    before_done: bool
    after_done: bool

    @property
    def blocked(self) -> bool:
        """True while a required test before the lesson is not submitted."""
        return self.before_exam is not None and not self.before_done


def lesson_gate(session: Session, lesson: Lesson, user: User) -> LessonGate:
    """The lesson's tests and whether the user has submitted each; tutors and admins are never held back."""
    before = session.get(Exam, lesson.before_exam_id) if lesson.before_exam_id else None
    after = session.get(Exam, lesson.after_exam_id) if lesson.after_exam_id else None
    exempt = user.role != Role.STUDENT
    return LessonGate(before, after, exempt or bool(before and _submitted(session, before.id, {user.id}, False)),
                      bool(after and _submitted(session, after.id, {user.id}, True)))


def require_before_test(session: Session, lesson: Lesson, user: User) -> None:
    """Refuses the lesson's robot commands until the user has submitted its test before (409)."""
    gate = lesson_gate(session, lesson, user)
    if gate.blocked and gate.before_exam is not None:
        raise Refused(409, "before_test_required", gettext("Take “%(title)s” first: this lesson compares what you "
                                                           "knew before it with what you know after.",
                                                           title=gate.before_exam.title), "before_exam_id")


def check_lesson_tests(session: Session, actor: User, before_id: int | None, after_id: int | None) -> None:
    """The tests a lesson names exist and the actor teaches their courses; before and after differ."""
    for name, exam_id in (("before_exam_id", before_id), ("after_exam_id", after_id)):
        exam = session.get(Exam, exam_id) if exam_id is not None else None
        if exam_id is not None and (exam is None or not teaches_course(session, actor, exam.course_id)):
            raise Refused(400, "invalid_field", gettext("%(name)s: choose a test of a course you teach.", name=name),
                                                name)
    if before_id is not None and before_id == after_id:
        raise Refused(400, "invalid_field", gettext("after_exam_id: choose another test than the one before, so "
                                                    "each student's two attempts are told apart."), "after_exam_id")


def teachable_exams(session: Session, actor: User) -> list[Exam]:
    """The tests a lesson's author may name: those of courses they teach (every one for an admin)."""
    exams = session.scalars(select(Exam).order_by(Exam.course_id, Exam.id)).all()
    return [e for e in exams if teaches_course(session, actor, e.course_id)]
