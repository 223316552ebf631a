"""Grades to the LMS's gradebook (AGS): a test's mark is queued when it is final and again after a tutor's
override, and an exercise's mark (an exercise attached to a course as a test) whenever it changes, in the
transaction that makes it (the outbox, lti_grade_passbacks), and sent after the commit.

- Queued per LMS line item of the test or the exercise's test (the line items the LMS named in launches of the
  placed link), for people the LMS knows (their LtiIdentity). A test sends the best final mark of the person's
  submitted attempts, as Telelab's own gradebook shows it; an exercise the student's mark on the course's test (their
  best graded submission begun before the deadline, in points, out of the test's points). A newer mark supersedes
  one still waiting.
- Sending claims a row with a conditional UPDATE (claimed_by, claimed_until), so one of several workers sends it;
  a failure keeps the row pending with the reason and the next try after a backoff (30 s doubling, at most an
  hour); the row survives restarts and any worker's GradeSender picks it up.
"""

from __future__ import annotations

import logging
import threading
import time
import uuid
from collections.abc import Callable
from datetime import UTC, datetime, timedelta

import requests
from flask import Flask, has_request_context
from pylti1p3.assignments_grades import AssignmentsGradesService
from pylti1p3.exception import LtiException
from pylti1p3.grade import Grade
from sqlalchemy import ColumnElement, func, or_, select, update
from sqlalchemy.orm import Session

from middleware import db
from middleware.assessment.review import final_score, reviews_of
from middleware.i18n import N_
from middleware.lti import services
from middleware.models.accounts import as_utc, utc_now
from middleware.models.assessment import Attempt
from middleware.models.exercises import ExerciseAssignment
from middleware.models.lti import LtiContext, LtiGradePassback, LtiIdentity, LtiLineItem, LtiPlatform

log = logging.getLogger(__name__)
SCORE_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
RETRY_BASE_S = 30.0
RETRY_MAX_S = 3600.0
CLAIM_S = 120.0
BATCH = 20


def best_final(session: Session, attempt: Attempt) -> tuple[float, float] | None:
    """(best final mark, maximum) over the person's submitted attempts at the attempt's test."""
    best: tuple[float, float] | None = None
    for other in session.scalars(select(Attempt).where(Attempt.exam_id == attempt.exam_id,
                                                       Attempt.user_id == attempt.user_id,
                                                       Attempt.status == "submitted")):
        score = final_score(other, reviews_of(session, other.id))
        if score is not None and (best is None or score > best[0]):
            best = (score, float(other.max_score or 0.0))
    return best


def _line_items(session: Session, user_id: int, graded_item: ColumnElement[bool]) -> list[LtiLineItem]:
    """The line items of graded_item (a column of LtiLineItem compared with an id) in the LMS that knows user_id."""
    issuer = session.scalar(select(LtiIdentity.issuer).where(LtiIdentity.user_id == user_id))
    if issuer is None:
        return []
    return list(session.scalars(select(LtiLineItem).join(LtiContext, LtiContext.id == LtiLineItem.context_id)
                                .where(graded_item, LtiContext.issuer == issuer).order_by(LtiLineItem.id)))


def _queue(session: Session, items: list[LtiLineItem], user_id: int, mark: tuple[float, float] | None,
           attempt_id: int | None = None) -> int:
    """Supersedes what still waits for user_id on items and queues mark (score, maximum) for each; the number."""
    for item in items:
        session.execute(update(LtiGradePassback).where(
            LtiGradePassback.line_item_id == item.id, LtiGradePassback.user_id == user_id,
            LtiGradePassback.status == "pending").values(status="superseded"))
        if mark is not None:
            session.add(LtiGradePassback(attempt_id=attempt_id, line_item_id=item.id, user_id=user_id,
                                         score_given=mark[0], score_maximum=mark[1], status="pending",
                                         next_try_at=utc_now()))
    session.flush()
    if mark is None or not items:
        return 0
    if has_request_context():
        db.after_commit(wake_senders)
    return len(items)


def queue_final_mark(session: Session, attempt: Attempt) -> int:
    """Queues the person's final mark at the test for every LMS line item it goes to; the number queued.
    Handed to assessment as its final-mark listener by create_app (assessment never imports lti)."""
    items = _line_items(session, attempt.user_id, LtiLineItem.exam_id == attempt.exam_id)
    mark = best_final(session, attempt) if items else None
    return _queue(session, items, attempt.user_id, mark, attempt.id) if mark is not None else 0


def queue_exercise_mark(session: Session, test: ExerciseAssignment, user_id: int, mark: float | None) -> int:
    """Queues a student's changed mark on an exercise's course test (in points, out of the test's points) for every
    LMS line item it goes to; the number queued. A mark that is gone (the deadline moved before every submission)
    or out of no points supersedes what waits and sends nothing: the LMS keeps what it was sent. Handed to exercises
    as its mark listener by create_app (exercises never imports lti)."""
    items = _line_items(session, user_id, LtiLineItem.exercise_assignment_id == test.id)
    score = (mark, float(test.points)) if mark is not None and test.points > 0 else None
    return _queue(session, items, user_id, score)


def queue_marks_of_new_line_item(session: Session, item: LtiLineItem, test: ExerciseAssignment,
                                 marks: dict[int, float]) -> int:
    """Queues the marks students already have (user id -> points) on an exercise's test whose line item the LMS just
    named, for those that LMS knows; the number queued."""
    context = session.get(LtiContext, item.context_id)
    if context is None or test.points <= 0 or not marks:
        return 0
    known = set(session.scalars(select(LtiIdentity.user_id).where(LtiIdentity.issuer == context.issuer,
                                                                 LtiIdentity.user_id.in_(list(marks)))))
    return sum(_queue(session, [item], user_id, (mark, float(test.points)))
               for user_id, mark in sorted(marks.items()) if user_id in known)


def _claim(session_factory: Callable[[], Session], now: datetime, key: str) -> list[int]:
    with session_factory() as session, session.begin():
        due = list(session.scalars(select(LtiGradePassback.id).where(
            LtiGradePassback.status == "pending", LtiGradePassback.next_try_at <= now,
            or_(LtiGradePassback.claimed_until.is_(None), LtiGradePassback.claimed_until < now))
            .order_by(LtiGradePassback.id).limit(BATCH)))
        claimed = []
        for row_id in due:
            taken = session.execute(update(LtiGradePassback).where(
                LtiGradePassback.id == row_id, LtiGradePassback.status == "pending",
                or_(LtiGradePassback.claimed_until.is_(None), LtiGradePassback.claimed_until < now))
                .values(claimed_by=key, claimed_until=now + timedelta(seconds=CLAIM_S)))
            if taken.rowcount:  # type: ignore[attr-defined]
                claimed.append(row_id)
        return claimed


def _send_one(session: Session, row: LtiGradePassback, http: requests.Session) -> None:
    item = session.get(LtiLineItem, row.line_item_id)
    context = session.get(LtiContext, item.context_id) if item else None
    platform = session.get(LtiPlatform, context.platform_id) if context else None
    subject = session.scalar(select(LtiIdentity.subject).where(LtiIdentity.user_id == row.user_id))
    if item is None or context is None or platform is None or subject is None:
        raise LtiException(N_("The LMS course or its registration is gone."))  # stored; said by services.said
    scopes = list(context.ags_scopes or []) or [SCORE_SCOPE]
    ags = AssignmentsGradesService(services.connector(session, platform, http),
                                   {"lineitem": item.lineitem_url, "scope": scopes})  # type: ignore[typeddict-item]
    grade = Grade().set_score_given(row.score_given).set_score_maximum(row.score_maximum) \
        .set_activity_progress("Completed").set_grading_progress("FullyGraded").set_user_id(subject) \
        .set_timestamp(datetime.now(UTC).isoformat())
    ags.put_grade(grade)


def send_due(session_factory: Callable[[], Session], now: datetime | None = None,
             http: requests.Session | None = None) -> tuple[int, int]:
    """Sends every grade due now that this process claims; (sent, failed)."""
    moment = now or utc_now()
    key = f"{uuid.uuid4().hex[:12]}"
    sent = failed = 0
    client = http or services.http_session()
    for row_id in _claim(session_factory, moment, key):
        with session_factory() as session:  # the send only reads; its outcome is written in a unit of its own
            row = session.get(LtiGradePassback, row_id)
            if row is None or row.claimed_by != key:
                continue
            try:
                _send_one(session, row, client)
                error = None
            except (LtiException, requests.RequestException, ValueError) as exc:
                error = services.failure_reason(exc)
        with session_factory() as session, session.begin():
            row = session.get(LtiGradePassback, row_id)
            if row is None:
                continue
            row.claimed_by, row.claimed_until = None, None
            row.tries += 1
            if error is None:
                row.status, row.sent_at, row.last_error = ("sent" if row.status == "pending" else row.status,
                                                           utc_now(), None)
                sent += 1
            else:
                delay = min(RETRY_BASE_S * 2 ** (row.tries - 1), RETRY_MAX_S)
                row.last_error, row.next_try_at = error, moment + timedelta(seconds=delay)
                failed += 1
                log.warning("LTI grade %s not sent (try %s): %s", row_id, row.tries, error)
    return sent, failed


def retry_now(session: Session, course_id: int) -> int:
    """Makes the course's waiting grades due at once (the tutor's "Retry now"); the number."""
    contexts = select(LtiContext.id).where(LtiContext.course_id == course_id)
    items = select(LtiLineItem.id).where(LtiLineItem.context_id.in_(contexts))
    result = session.execute(update(LtiGradePassback).where(
        LtiGradePassback.line_item_id.in_(items), LtiGradePassback.status == "pending")
        .values(next_try_at=utc_now()))
    if has_request_context():
        db.after_commit(wake_senders)
    return int(result.rowcount)  # type: ignore[attr-defined]


def pending_count(session: Session) -> int:
    """Grades waiting to be sent, in the whole lab."""
    return int(session.scalar(select(func.count()).select_from(LtiGradePassback)
                              .where(LtiGradePassback.status == "pending")) or 0)


def next_due(session: Session) -> datetime | None:
    """When the next waiting grade is due."""
    moment = session.scalar(select(func.min(LtiGradePassback.next_try_at))
                            .where(LtiGradePassback.status == "pending"))
    return as_utc(moment) if moment is not None else None


_senders: list[GradeSender] = []


def wake_senders() -> None:
    """Wakes this process's grade senders (after a commit that queued grades)."""
    for sender in list(_senders):
        sender.wake()


class GradeSender:
    """Sends queued grades from a thread that runs only while some are waiting (started again when woken)."""

    IDLE_CHECK_S = 30.0
    MAX_WAIT_S = 5.0

    def __init__(self, app: Flask) -> None:
        self._factory = db.session_factory(app)
        self._lock = threading.Lock()
        self._woken = threading.Event()
        self._thread: threading.Thread | None = None
        self._checked_at = 0.0
        self._stopped = False
        _senders.append(self)

    def stop(self) -> None:
        """Stops for good (the app is closing)."""
        self._stopped = True
        self._woken.set()
        if self in _senders:
            _senders.remove(self)

    def wake(self) -> None:
        """Sends what is due now, starting the thread if it is not running."""
        with self._lock:
            self._checked_at = time.monotonic()
            if self._stopped:
                return
            self._woken.set()
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._run, name="lti-grade-sender", daemon=True)
                self._thread.start()

    def maybe_wake(self) -> None:
        """Wakes the sender at most every IDLE_CHECK_S (each request calls it: grades queued elsewhere, or left
        by a process that stopped, are sent)."""
        if time.monotonic() - self._checked_at >= self.IDLE_CHECK_S:
            self.wake()

    def _run(self) -> None:
        while not self._stopped:
            self._woken.clear()
            try:
                send_due(self._factory)
                with self._factory() as session:
                    due = next_due(session)
            except Exception:  # noqa: BLE001 - a database away: the next request's maybe_wake tries again
                log.exception("LTI grade sender")
                return
            if due is None:
                return
            wait = min(max((due - utc_now()).total_seconds(), 0.05), self.MAX_WAIT_S)
            self._woken.wait(wait)
