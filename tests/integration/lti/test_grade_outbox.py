"""The grade outbox on SQLite and PostgreSQL: two workers sending at once claim disjoint rows, each row is sent
once, and a failed row keeps the LMS's reason and waits (the LMS here is a stand-in HTTP session: only the
database's part is under test; tests/integration/lti/test_services.py sends to a real test LMS)."""

from __future__ import annotations

import threading
from datetime import timedelta

import requests
from sqlalchemy import select
from sqlalchemy.orm import sessionmaker

from middleware.lti import grades
from middleware.models import Course, User
from middleware.models.accounts import utc_now
from middleware.models.assessment import Attempt, Exam
from middleware.models.lti import LtiContext, LtiGradePassback, LtiIdentity, LtiLineItem, LtiPlatform


class _CountingLms(requests.Session):
    """Answers every request 200 with a token, counting score posts (a stand-in: the database is under test)."""

    def __init__(self, fail: bool = False) -> None:
        super().__init__()
        self.posted: list[str] = []
        self.fail = fail
        self._lock = threading.Lock()

    def request(self, method, url, *args, **kwargs):  # type: ignore[no-untyped-def, override]
        """A canned answer."""
        response = requests.Response()
        response.url = url
        if url.endswith("/token"):
            response.status_code, response._content = 200, b'{"access_token": "t"}'
        elif self.fail:
            response.status_code, response._content, response.reason = 503, b"gradebook down", "Service Unavailable"
        else:
            with self._lock:
                self.posted.append(url)
            response.status_code, response._content = 200, b""
        return response


def _outbox(session_factory: sessionmaker, rows: int) -> None:
    with session_factory() as session, session.begin():
        platform = LtiPlatform(name="LMS", issuer="https://lms.example", client_id="c", frame_origins=[],
                               auth_login_url="https://lms.example/auth", auth_token_url="https://lms.example/token",
                               key_set_url="https://lms.example/jwks")
        course = Course(code="C1", title="C1")
        session.add_all([platform, course])
        session.flush()
        context = LtiContext(platform_id=platform.id, issuer=platform.issuer, context_id="c1", course_id=course.id,
                             ags_scopes=[grades.SCORE_SCOPE])
        exam = Exam(course_id=course.id, title="t", kind="quiz", question_ids=[])
        session.add_all([context, exam])
        session.flush()
        item = LtiLineItem(context_id=context.id, exam_id=exam.id, lineitem_url="https://lms.example/lineitems/1")
        session.add(item)
        for n in range(rows):
            user = User(username=f"u{n}", role="student", password_hash="x")
            session.add(user)
            session.flush()
            session.add(LtiIdentity(issuer=platform.issuer, subject=f"s{n}", user_id=user.id))
            attempt = Attempt(exam_id=exam.id, user_id=user.id, status="submitted", started_at=utc_now())
            session.add(attempt)
            session.flush()
            session.add(LtiGradePassback(attempt_id=attempt.id, line_item_id=item.id, user_id=user.id,
                                         score_given=1.0, score_maximum=2.0, status="pending", next_try_at=utc_now()))


def test_two_workers_send_every_grade_once_and_a_failure_keeps_its_reason(engine) -> None:
    factory = sessionmaker(bind=engine, expire_on_commit=False)
    _outbox(factory, 12)
    lms = _CountingLms()
    outcomes: list[tuple[int, int]] = []
    workers = [threading.Thread(target=lambda: outcomes.append(grades.send_due(factory, http=lms)))
               for _ in range(2)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(60)
    assert sum(sent for sent, _ in outcomes) == 12 and len(lms.posted) == 12
    with factory() as session:
        assert set(session.scalars(select(LtiGradePassback.status))) == {"sent"}

    with factory() as session, session.begin():
        row = session.scalars(select(LtiGradePassback)).first()
        assert row is not None
        row.status, row.next_try_at = "pending", utc_now()
    assert grades.send_due(factory, http=_CountingLms(fail=True)) == (0, 1)
    with factory() as session:
        failed = session.scalars(select(LtiGradePassback).where(LtiGradePassback.status == "pending")).one()
        assert failed.last_error == "The LMS answered 503 Service Unavailable: gradebook down"
        assert failed.tries == 2 and failed.claimed_by is None
        waited = failed.next_try_at - utc_now() if failed.next_try_at.tzinfo else None
    assert waited is None or waited > timedelta(seconds=20)
    assert grades.send_due(factory, http=lms) == (0, 0)  # not due yet
    # Its backoff over, the sender's next pass sends it with nobody asking (the tutor's "Retry now" only hastens it).
    assert grades.send_due(factory, now=utc_now() + timedelta(seconds=61), http=lms) == (1, 0)
    with factory() as session:
        assert set(session.scalars(select(LtiGradePassback.status))) == {"sent"}
