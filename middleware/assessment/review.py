"""The online test corrector: attempt views, tutors' overrides with a reason, comments, and the grades export."""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.assessment.attempts import _items, final_mark_changed, my_attempts, settle, settle_due, window_state
from middleware.assessment.bank import list_exams, managed_exam, question_dict, questions_of
from middleware.assessment.policy import may_teach, readable_attempt, teaching_course
from middleware.courses.schemas import csv_safe
from middleware.errors import Refused, written_number
from middleware.models import CourseMembership, User
from middleware.models.accounts import as_utc
from middleware.models.assessment import Attempt, AttemptReview, Exam, Question


def final_results(attempt: Attempt, reviews: list[AttemptReview]) -> list[dict[str, Any]]:
    """The automatic results with each item's latest override applied (and its reason)."""
    latest = {r.item: r for r in sorted(reviews, key=lambda r: r.id) if r.points is not None and r.item}
    out = []
    for result in attempt.results or []:
        item = dict(result)
        override = latest.get(result["item"])
        if override is not None:
            item.update(auto_points=result["points"], points=override.points, override_reason=override.reason)
        out.append(item)
    return out


def final_score(attempt: Attempt, reviews: list[AttemptReview]) -> float | None:
    """The attempt's mark after overrides (None while in progress)."""
    if attempt.status != "submitted":
        return None
    return round(sum(float(r["points"]) for r in final_results(attempt, reviews)), 4)


@dataclass(frozen=True)
class MarkedAttempt:
    """One of a student's attempts as their lists show it: the mark is the final one (after any override)."""

    id: int
    status: str
    started_at: datetime
    score: float | None
    max_score: float | None


def my_marked_attempts(session: Session, user_id: int, exam_id: int) -> list[MarkedAttempt]:
    """A student's attempts at an exam, newest first, each with its final mark (None while in progress)."""
    return [MarkedAttempt(a.id, a.status, a.started_at, final_score(a, reviews_of(session, a.id)), a.max_score)
            for a in my_attempts(session, user_id, exam_id)]


def item_labels(questions: list[Question]) -> dict[str, str]:
    """Each item's name as the attempt shows it: questions by their place in the test, not their bank number."""
    labels = {str(q.id): gettext("Question %(place)s", place=place) for place, q in enumerate(questions, start=1)}
    labels["task"] = gettext("Experimental task")
    return labels


def reviews_of(session: Session, attempt_id: int) -> list[AttemptReview]:
    """The attempt's overrides and comments, oldest first."""
    return list(session.scalars(select(AttemptReview).where(AttemptReview.attempt_id == attempt_id)
                                .order_by(AttemptReview.id)))


def attempt_view(session: Session, actor: User, attempt_id: int, now: datetime) -> dict[str, Any]:
    """An attempt as its student or a tutor sees it; keys and marks only once submitted; never the trace."""
    attempt, exam = readable_attempt(session, actor, attempt_id)
    settle(session, attempt, now)
    reviews = reviews_of(session, attempt.id)
    submitted = attempt.status == "submitted"
    names = dict(session.execute(select(User.id, User.username).where(
        User.id.in_({r.author_id for r in reviews} | {attempt.user_id}))).all())
    questions = questions_of(session, exam)
    remaining = None
    if not submitted and attempt.deadline_at is not None:
        remaining = max(0.0, (as_utc(attempt.deadline_at) - now).total_seconds())
    return {
        "id": attempt.id, "exam": {**exam_dict(exam, now), "robot_name": attempt.robot_name or exam.robot_name},
        "student": names.get(attempt.user_id),
        "status": attempt.status, "started_at": as_utc(attempt.started_at).isoformat(),
        "deadline_at": as_utc(attempt.deadline_at).isoformat() if attempt.deadline_at else None,
        "remaining_s": remaining, "server_now": now.isoformat(),
        "submitted_at": as_utc(attempt.submitted_at).isoformat() if attempt.submitted_at else None,
        "submitted_by": attempt.submitted_by,
        "questions": [question_dict(q, with_key=False) for q in questions],
        "labels": item_labels(questions),
        "items": sorted(_items(exam)),
        "answers": attempt.answers or {},
        "results": final_results(attempt, reviews) if submitted else None,
        "score": final_score(attempt, reviews), "max_score": attempt.max_score,
        "reviews": [{"id": r.id, "author": names.get(r.author_id), "item": r.item, "points": r.points,
                     "reason": r.reason, "comment": r.comment, "at": as_utc(r.created_at).isoformat()}
                    for r in reviews],
    }


def task_goal(task: dict[str, Any], robot_name: str | None) -> str:
    """The task's goal in one sentence, stated once by the page; the tutor's instructions add to it."""
    robot = robot_name or gettext("the robot")
    if task.get("kind") == "reach_point":
        return str(gettext("Bring %(robot)s to (%(x)s, %(y)s) m, then submit.", robot=robot,
                           x=written_number(task.get("x_m")), y=written_number(task.get("y_m"))))
    if task.get("kind") == "wall_following":
        return str(gettext("Follow the wall at %(distance)s m, then submit.",
                           distance=written_number(task.get("distance_m"))))
    return ""


def exam_dict(exam: Exam, now: datetime) -> dict[str, Any]:
    """An exam as lists show it (no keys)."""
    task = None
    if exam.task:
        task = {k: v for k, v in exam.task.items() if k in ("kind", "instructions", "points", "x_m", "y_m",
                                                             "distance_m", "rubric")}
        task["goal"] = task_goal(exam.task, exam.robot_name)
    return {"id": exam.id, "course_id": exam.course_id, "title": exam.title, "kind": exam.kind,
            "opens_at": as_utc(exam.opens_at).isoformat() if exam.opens_at else None,
            "closes_at": as_utc(exam.closes_at).isoformat() if exam.closes_at else None,
            "duration_s": exam.duration_s, "max_attempts": exam.max_attempts, "question_ids": exam.question_ids,
            "robot_name": exam.robot_name, "task": task, "state": window_state(exam, now)}


def list_attempts(session: Session, actor: User, exam_id: int, now: datetime) -> list[dict[str, Any]]:
    """Every attempt at an exam with its student and mark (the course's tutors, admins)."""
    exam = managed_exam(session, actor, exam_id)
    settle_due(session, now, exam_id=exam.id)
    rows = session.execute(select(Attempt, User.username).join(User, User.id == Attempt.user_id)
                           .where(Attempt.exam_id == exam.id).order_by(User.username, Attempt.id)).all()
    out = []
    for attempt, username in rows:
        reviews = reviews_of(session, attempt.id)
        out.append({"id": attempt.id, "student": username, "status": attempt.status,
                    "submitted_at": as_utc(attempt.submitted_at).isoformat() if attempt.submitted_at else None,
                    "submitted_by": attempt.submitted_by, "auto_score": attempt.auto_score,
                    "score": final_score(attempt, reviews), "max_score": attempt.max_score,
                    "reviewed": any(r.points is not None for r in reviews)})
    return out


def _reviewable(session: Session, actor: User, attempt_id: int, now: datetime) -> Attempt:
    attempt, exam = readable_attempt(session, actor, attempt_id)
    if not may_teach(session, actor, exam.course_id):
        raise Refused(403, "forbidden", gettext("Only the course's tutors review attempts."))
    settle(session, attempt, now)
    if attempt.status != "submitted":
        raise Refused(409, "not_submitted", gettext("The attempt is still in progress; review it once submitted."),
                      "attempt_id")
    return attempt


def override_mark(session: Session, actor: User, attempt_id: int, item: object, points: object, reason: object,
                  comment: object, now: datetime) -> AttemptReview:
    """Replaces one item's mark; the reason is required and kept, the automatic mark stays visible."""
    attempt = _reviewable(session, actor, attempt_id, now)
    result = next((r for r in attempt.results or [] if r["item"] == str(item)), None)
    if result is None:
        raise Refused(400, "invalid_field", gettext("Choose an item of this attempt."), "item")
    try:  # typed on the page as the tutor's language writes it: 0.5, or 0,5 in Spanish
        value = float(points.strip().replace(",", ".") if isinstance(points, str) else points)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        value = float("nan")
    if not 0 <= value <= float(result["max_points"]):
        raise Refused(400, "invalid_field", gettext("points must be from 0 to %(max_points)s.",
                                                    max_points=written_number(result["max_points"], "g")), "points")
    if not isinstance(reason, str) or not reason.strip() or len(reason) > 2000:
        raise Refused(400, "invalid_field", gettext("Say why the mark changes (1 to 2000 characters)."), "reason")
    text = comment.strip() if isinstance(comment, str) else ""
    review = AttemptReview(attempt_id=attempt.id, author_id=actor.id, item=str(item), points=round(value, 4),
                           reason=reason.strip(), comment=text[:4000], created_at=now)
    session.add(review)
    session.flush()
    final_mark_changed(session, attempt)
    return review


def add_comment(session: Session, actor: User, attempt_id: int, item: object, comment: object,
                now: datetime) -> AttemptReview:
    """A tutor's comment on the attempt (item None) or on one item."""
    attempt = _reviewable(session, actor, attempt_id, now)
    if not isinstance(comment, str) or not comment.strip() or len(comment) > 4000:
        raise Refused(400, "invalid_field", gettext("Write a comment of 1 to 4000 characters."), "comment")
    if item not in (None, "") and str(item) not in {r["item"] for r in attempt.results or []}:
        raise Refused(400, "invalid_field", gettext("Choose an item of this attempt."), "item")
    review = AttemptReview(attempt_id=attempt.id, author_id=actor.id, item=str(item) if item else None,
                           points=None, reason="", comment=comment.strip(), created_at=now)
    session.add(review)
    session.flush()
    return review


def best_scores(session: Session, course_id: int, now: datetime) -> dict[tuple[int, int], float]:
    """(user id, exam id) -> the best final mark of the user's submitted attempts."""
    settle_due(session, now)
    best: dict[tuple[int, int], float] = {}
    attempts = session.scalars(select(Attempt).join(Exam, Exam.id == Attempt.exam_id)
                               .where(Exam.course_id == course_id, Attempt.status == "submitted"))
    for attempt in list(attempts):
        score = final_score(attempt, reviews_of(session, attempt.id)) or 0.0
        key = (attempt.user_id, attempt.exam_id)
        best[key] = max(best.get(key, 0.0), score)
    return best


@dataclass(frozen=True)
class Gradebook:
    """The course's tests (columns) and, per student, the best final mark at each (None: no submitted attempt)."""

    exams: list[Exam]
    rows: list[tuple[str, list[float | None]]]


def gradebook(session: Session, actor: User, course_id: int, now: datetime) -> Gradebook:
    """Every student of the course against every test, best final marks (the course's tutors, admins)."""
    teaching_course(session, actor, course_id)
    exams = list_exams(session, course_id)
    students = session.execute(select(User.id, User.username)
                               .join(CourseMembership, CourseMembership.user_id == User.id)
                               .where(CourseMembership.course_id == course_id, CourseMembership.role == "student")
                               .order_by(User.username)).all()
    best = best_scores(session, course_id, now)
    return Gradebook(exams, [(username, [best.get((user_id, e.id)) for e in exams]) for user_id, username in students])


def grades_csv(session: Session, actor: User, course_id: int, now: datetime) -> str:
    """One row per student, one column per exam (best final mark out of its maximum), every cell formula-safe."""
    book = gradebook(session, actor, course_id, now)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    writer.writerow(["username", *[csv_safe(f"{e.title} ({e.kind})") for e in book.exams]])
    for username, marks in book.rows:
        writer.writerow([csv_safe(username), *["" if mark is None else f"{mark:g}" for mark in marks]])
    return out.getvalue()
