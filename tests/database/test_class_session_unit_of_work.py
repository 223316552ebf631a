"""Opening a class session never ends its caller's unit of work: a session another tutor opened at the same moment
is refused, and the caller (the request's handler, or the class-bookings keeper) rolls back (issue 28)."""

from __future__ import annotations

import pytest
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from middleware.errors import Refused
from middleware.models import Course, CourseMembership
from middleware.models.farm import ClassSession
from middleware.teaching import class_sessions
from tests.conftest import add_test_account


class RoomyFarm:
    """Stands in for the practice manager: start_session only asks how many robots fit (no robot starts here)."""

    def limit(self) -> int:
        return 10

    def count(self) -> int:
        return 0


def test_a_session_opened_at_the_same_moment_is_refused_without_rolling_back_the_callers_session(
        engine: Engine, monkeypatch: pytest.MonkeyPatch) -> None:
    with Session(engine) as session, session.begin():
        tutor, student = add_test_account(session, "tess", "tutor"), add_test_account(session, "sam", "student")
        course = Course(code="C1", title="Course one")
        session.add(course)
        session.flush()
        session.add_all([CourseMembership(course_id=course.id, user_id=tutor.id, role="tutor"),
                         CourseMembership(course_id=course.id, user_id=student.id, role="student"),
                         ClassSession(course_id=course.id, started_by_id=tutor.id)])  # the other tutor's, committed
        course_id, tutor_id = course.id, tutor.id
    # The race: this request's check for an open session ran before the other tutor's commit.
    monkeypatch.setattr(class_sessions, "open_session", lambda _session, _course_id: None)
    with Session(engine) as session:
        rollbacks: list[bool] = []
        rollback = session.rollback
        monkeypatch.setattr(session, "rollback", lambda: (rollbacks.append(True), rollback())[1])
        tutor = session.get(class_sessions.User, tutor_id)
        assert tutor is not None
        with pytest.raises(Refused) as refused:
            class_sessions.start_session(session, tutor, course_id, RoomyFarm())  # type: ignore[arg-type]
        assert (refused.value.status, refused.value.code) == (409, "class_session_open")
        assert rollbacks == [], "the caller's unit of work is the caller's to end"
        session.rollback()
