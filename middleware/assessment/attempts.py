"""Attempts: start, save answers as they go, submit, and the deadline. Every rule takes `now` from the server.

- One attempt in progress per student and exam: Attempt.open_key ("<exam>:<user>") is unique while set, so a
  second start in another worker process fails in the database; starts also lock the student's row.
- A timed attempt's deadline is min(started + duration, closes_at). An answer or a submission arriving after it
  is refused (TimeUp), and the attempt is submitted as it stood at the deadline ("settled"). Any read of the
  attempt settles it too, so an attempt nobody comes back to is submitted at the next look (lists, the tutor's
  page, the grades export).
- A submitted attempt never changes: answers, trace and automatic results are written once; tutors' overrides
  and comments are separate rows (review.py).
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import datetime, timedelta
from typing import Any

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import func, or_, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.accounts.services import forbidden
from middleware.assessment import hidden_obstacles, obstacle_zone
from middleware.assessment.bank import questions_of
from middleware.assessment.grading import ItemResult, grade_question
from middleware.assessment.policy import get_attempt, get_exam, student_course
from middleware.assessment.rating import read_rating
from middleware.assessment.trace_grading import MAX_TRACE_SAMPLES, grade_task
from middleware.auth.schemas import InvalidField
from middleware.errors import Refused
from middleware.locking import lock_user, rows_matched
from middleware.models import User
from middleware.models.accounts import as_utc
from middleware.models.assessment import Attempt, Exam

# Where a settled experimental attempt's run comes from: the robot's own pose log over the attempt (its routes
# hand the reader in); None: the trace stored so far is graded.
RunSource = Callable[[str, datetime, datetime], "list[list[float]] | None"]
_run_source: RunSource | None = None
# Who hears that a mark became final (submitted, or a tutor's override), in the transaction that makes it:
# create_app hands the listeners in (the LTI grade passback), so assessment imports none of them.
FinalMarkListener = Callable[[Session, Attempt], object]
_final_mark_listeners: list[FinalMarkListener] = []

MAX_ANSWER_CHARS = 4000


class TimeUp(Refused):
    """The deadline has passed: the answer is refused, and the attempt was submitted as it stood (that stays)."""

    keeps_changes = True

    def __init__(self) -> None:
        super().__init__(409, "time_up", "The time for this attempt is up: it was submitted as it stood at the "
                                         "deadline, and later answers are not accepted.", "answers")


def window_state(exam: Exam, now: datetime) -> str:
    """upcoming, open or closed: where now falls in the exam's window (no window: always open)."""
    if exam.opens_at is not None and now < as_utc(exam.opens_at):
        return "upcoming"
    if exam.closes_at is not None and now >= as_utc(exam.closes_at):
        return "closed"
    return "open"


def _lock_attempt(session: Session, attempt_id: int) -> Attempt:
    """The attempt, its row locked until the transaction ends (SQLite: the write lock), fresh from the database."""
    if session.get_bind().dialect.name == "sqlite":
        session.execute(update(Attempt).where(Attempt.id == attempt_id).values(id=Attempt.id))
    else:
        session.execute(select(Attempt.id).where(Attempt.id == attempt_id).with_for_update())
    attempt = get_attempt(session, attempt_id)
    session.refresh(attempt)
    return attempt


def grade_attempt(session: Session, exam: Exam, answers: dict[str, Any],
                  trace: list[list[float]] | None) -> list[ItemResult]:
    """The automatic marks of every item of the attempt."""
    results = [grade_question(str(q.id), q.kind, q.spec, q.points, answers.get(str(q.id)), tuple(q.topics))
               for q in questions_of(session, exam)]
    if exam.kind == "experimental" and exam.task:
        item = obstacle_zone.ZONE_ITEM if exam.task.get("kind") == obstacle_zone.TASK_KIND else "report"
        results.append(grade_task(exam.task, float(exam.task.get("points", 10)), trace or [], answers.get(item)))
    return results


def read_runs_from(source: RunSource) -> None:
    """Makes source(robot_name, started, deadline) the run an attempt settled at its deadline is graded on."""
    global _run_source
    _run_source = source


def on_final_mark(listener: FinalMarkListener) -> None:
    """Makes listener(session, attempt) hear of every final mark and every override (once, however often given)."""
    if listener not in _final_mark_listeners:
        _final_mark_listeners.append(listener)


def final_mark_changed(session: Session, attempt: Attempt) -> None:
    """Tells the listeners that attempt's final mark is set or changed."""
    for listener in _final_mark_listeners:
        listener(session, attempt)


def _run_until_deadline(exam: Exam, attempt: Attempt, deadline: datetime) -> list[list[float]] | None:
    robot_name = attempt.robot_name or exam.robot_name
    if exam.kind != "experimental" or not robot_name or _run_source is None:
        return None
    return _run_source(robot_name, as_utc(attempt.started_at), deadline)


def _is_zone_test(exam: Exam) -> bool:
    return exam.kind == "experimental" and (exam.task or {}).get("kind") == obstacle_zone.TASK_KIND


def _finalise(session: Session, exam: Exam, attempt: Attempt, at: datetime, by: str,
              trace: list[list[float]] | None) -> None:
    if trace is None and by == "deadline":
        trace = _run_until_deadline(exam, attempt, at)  # whichever worker recorded, and whether it lived
    if trace is not None:
        attempt.trace = trace[-MAX_TRACE_SAMPLES:]
    if _is_zone_test(exam):
        hidden_obstacles.announce_change(session, attempt.user_id)  # the obstacles come back at once
    results = grade_attempt(session, exam, attempt.answers or {}, attempt.trace)
    attempt.results = [r.to_dict() for r in results]
    attempt.auto_score = round(sum(r.points for r in results), 4)
    attempt.max_score = round(sum(r.max_points for r in results), 4)
    attempt.status, attempt.open_key, attempt.submitted_at, attempt.submitted_by = "submitted", None, at, by
    session.flush()
    final_mark_changed(session, attempt)


def settle(session: Session, attempt: Attempt, now: datetime) -> bool:
    """Submits the attempt as it stands when its deadline has passed; True when it did."""
    if attempt.status != "in_progress" or attempt.deadline_at is None or now <= as_utc(attempt.deadline_at):
        return False
    attempt = _lock_attempt(session, attempt.id)
    if attempt.status != "in_progress" or attempt.deadline_at is None:
        return False
    _finalise(session, get_exam(session, attempt.exam_id), attempt, as_utc(attempt.deadline_at), "deadline", None)
    return True


def settle_due(session: Session, now: datetime, *, exam_id: int | None = None, user_id: int | None = None) -> int:
    """Settles every overdue attempt of an exam or a user; the number settled."""
    query = select(Attempt).where(Attempt.status == "in_progress", Attempt.deadline_at.is_not(None),
                                  Attempt.deadline_at < now)
    if exam_id is not None:
        query = query.where(Attempt.exam_id == exam_id)
    if user_id is not None:
        query = query.where(Attempt.user_id == user_id)
    return sum(settle(session, attempt, now) for attempt in list(session.scalars(query)))


def start_attempt(session: Session, actor: User, exam_id: int, now: datetime,
                  controls_robot: Callable[[str, int], bool] | None = None,
                  own_robot: Callable[[Exam, int], str | None] | None = None) -> Attempt:
    """The student's attempt in progress, or a new one when the window is open and attempts remain.

    An experimental test runs on the student's own robot when own_robot names one (their robot in a class
    session of the course), else on the exam's robot, which they must control."""
    exam = get_exam(session, exam_id)
    student_course(session, actor, exam.course_id)
    lock_user(session, actor.id)
    settle_due(session, now, exam_id=exam.id, user_id=actor.id)
    current = session.scalar(select(Attempt).where(Attempt.open_key == f"{exam.id}:{actor.id}"))
    if current is not None:
        return current
    state = window_state(exam, now)
    if state != "open":
        raise Refused(409, f"exam_{state}", gettext("This test is not open yet.") if state == "upcoming"
                      else gettext("This test has closed; no new attempts are accepted."), "exam_id")
    done = session.scalar(select(func.count()).select_from(Attempt).where(
        Attempt.exam_id == exam.id, Attempt.user_id == actor.id)) or 0
    if exam.max_attempts is not None and done >= exam.max_attempts:
        raise Refused(409, "no_attempts_left", gettext("You have used your %(max_attempts)s attempt(s) at this test.",
                                                       max_attempts=exam.max_attempts),
                      "exam_id")
    robot_name = None
    if exam.kind == "experimental":
        robot_name = (own_robot(exam, actor.id) if own_robot else None) or exam.robot_name
        if robot_name == exam.robot_name and (controls_robot is None or not controls_robot(robot_name or "",
                                                                                            actor.id)):
            raise Refused(409, "no_robot", gettext("Take control of %(robot_name)s first (open it in the lab, or "
                                                   "during your booking), then start the test.",
                                                   robot_name=exam.robot_name), "robot_name")
    deadline = None
    if exam.duration_s is not None:
        deadline = now + timedelta(seconds=exam.duration_s)
    if exam.closes_at is not None:
        deadline = min(deadline or as_utc(exam.closes_at), as_utc(exam.closes_at))
    attempt = Attempt(exam_id=exam.id, user_id=actor.id, status="in_progress", open_key=f"{exam.id}:{actor.id}",
                      started_at=now, deadline_at=deadline, answers={}, robot_name=robot_name)
    session.add(attempt)
    try:
        session.flush()
    except IntegrityError:
        raise Refused(409, "attempt_in_progress", lazy_gettext("An attempt at this test is already in progress."),
                      "exam_id") from None
    if _is_zone_test(exam):
        hidden_obstacles.announce_change(session, actor.id)
    return attempt


def _own_open_attempt(session: Session, actor: User, attempt_id: int, now: datetime) -> tuple[Attempt, Exam]:
    attempt = _lock_attempt(session, attempt_id)
    if attempt.user_id != actor.id:
        raise forbidden(gettext("You can answer only your own attempts."))
    exam = get_exam(session, attempt.exam_id)
    if attempt.status != "in_progress":
        raise Refused(409, "already_submitted", gettext("This attempt was submitted; it cannot change."), "attempt_id")
    if attempt.deadline_at is not None and now > as_utc(attempt.deadline_at):
        _finalise(session, exam, attempt, as_utc(attempt.deadline_at), "deadline", None)
        raise TimeUp()
    return attempt, exam


def _clean_answer(exam_items: set[str], item: str, answer: object, started: datetime, now: datetime) -> object:
    if item not in exam_items:
        raise Refused(400, "invalid_field", gettext("%(item)s is not a question of this test.", item=item), "item")
    if item == "report":
        if not isinstance(answer, dict):
            raise Refused(400, "invalid_field", gettext("A pose report is {x_m, y_m}."), "report")
        # The moment of the report is the server's, never the browser's.
        return {"x_m": answer.get("x_m"), "y_m": answer.get("y_m"), "t_s": (now - started).total_seconds()}
    if item == obstacle_zone.ZONE_ITEM:
        return obstacle_zone.clean_zone(answer)
    if len(repr(answer)) > MAX_ANSWER_CHARS:
        raise Refused(400, "invalid_field", gettext("The answer is too long."), item)
    if answer is not None and not isinstance(answer, str | int | float | list | dict):
        raise Refused(400, "invalid_field", gettext("The answer has an unknown shape."), item)
    return answer


def _clean_rating(item: str, answer: object) -> int:
    try:
        return read_rating(answer, item)
    except InvalidField:
        raise Refused(400, "invalid_field", gettext("Question %(item)s: choose a rating from 1 to 5.", item=item),
                                            item) from None


def _items(exam: Exam) -> set[str]:
    items = {str(i) for i in exam.question_ids or []}
    if exam.kind == "experimental" and exam.task and exam.task.get("kind") == "report_pose":
        items.add("report")
    if _is_zone_test(exam):
        items.add(obstacle_zone.ZONE_ITEM)
    return items


def save_answers(session: Session, actor: User, attempt_id: int, answers: dict[str, object],
                 now: datetime) -> Attempt:
    """Stores answers (item -> answer) in the student's attempt in progress, before its deadline."""
    attempt, exam = _own_open_attempt(session, actor, attempt_id, now)
    items = _items(exam)
    ratings = {str(q.id) for q in questions_of(session, exam) if q.kind == "rating"}
    merged = dict(attempt.answers or {})
    for item, answer in answers.items():
        merged[str(item)] = _clean_answer(items, str(item), answer, as_utc(attempt.started_at), now)
        if str(item) in ratings and answer not in (None, ""):
            merged[str(item)] = _clean_rating(str(item), answer)
    attempt.answers = merged
    session.flush()
    return attempt


def submit_attempt(session: Session, actor: User, attempt_id: int, now: datetime,
                   answers: dict[str, object] | None = None, trace: list[list[float]] | None = None) -> Attempt:
    """Saves the last answers and submits the attempt; it is graded at once and never changes again."""
    if answers:
        save_answers(session, actor, attempt_id, answers, now)
    attempt, exam = _own_open_attempt(session, actor, attempt_id, now)
    _finalise(session, exam, attempt, now, "student", trace)
    return attempt


def record_trace(session: Session, attempt_id: int, trace: list[list[float]], recorder_key: str,
                 now: datetime) -> bool:
    """Stores the recorder's samples so far in an attempt still in progress that this recorder still holds (a
    conditional UPDATE); False: the attempt ended, or another process took the recording over."""
    done = rows_matched(session, update(Attempt).where(Attempt.id == attempt_id, Attempt.status == "in_progress",
                                                       Attempt.recorder_key == recorder_key)
                        .values(trace=trace[-MAX_TRACE_SAMPLES:], recorder_heard_at=now))
    return bool(done)


def claim_recording(session: Session, attempt_id: int, recorder_key: str, now: datetime,
                    stale_before: datetime) -> list[list[float]] | None:
    """Makes recorder_key the attempt's recorder if nobody records it or its recorder went quiet before
    stale_before (its process died); the trace stored so far, or None when another recorder holds it."""
    done = rows_matched(session, update(Attempt).where(
        Attempt.id == attempt_id, Attempt.status == "in_progress",
        or_(Attempt.recorder_key.is_(None), Attempt.recorder_key == recorder_key,
            Attempt.recorder_heard_at.is_(None), Attempt.recorder_heard_at < stale_before))
        .values(recorder_key=recorder_key, recorder_heard_at=now))
    if not done:
        return None
    return list(session.scalar(select(Attempt.trace).where(Attempt.id == attempt_id)) or [])


def orphaned_recordings(session: Session, stale_before: datetime) -> list[tuple[int, str]]:
    """(attempt id, robot) of experimental attempts in progress whose recorder went quiet before stale_before."""
    rows = session.execute(
        select(Attempt.id, func.coalesce(Attempt.robot_name, Exam.robot_name))
        .join(Exam, Exam.id == Attempt.exam_id)
        .where(Attempt.status == "in_progress", Exam.kind == "experimental", Attempt.recorder_key.is_not(None),
               Attempt.recorder_heard_at < stale_before))
    return [(attempt_id, robot) for attempt_id, robot in rows if robot]


def my_attempts(session: Session, user_id: int, exam_id: int) -> list[Attempt]:
    """A student's attempts at an exam, newest first."""
    return list(session.scalars(select(Attempt).where(Attempt.exam_id == exam_id, Attempt.user_id == user_id)
                                .order_by(Attempt.id.desc())))
