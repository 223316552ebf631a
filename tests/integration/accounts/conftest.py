"""Accounts in two courses on the live app (the bookings fixtures), and a snapshot of what may change."""

from __future__ import annotations

import pytest

from tests.integration.bookings.conftest import api, client_as, course_people

__all__ = ["api", "client_as", "course_people", "snapshot"]


@pytest.fixture
def snapshot(app):
    """A function returning everything an account or course action could change, to compare before/after."""
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, Invitation, Robot, User

    def take() -> tuple[object, ...]:
        with session_factory(app)() as session:
            return (
                sorted(session.execute(select(User.username, User.role, User.is_active, User.password_hash)).all()),
                sorted(session.execute(select(Course.code, Course.title, Course.turn_length_s,
                                              Course.booking_allowance_min)).all()),
                sorted(session.execute(select(CourseMembership.course_id, CourseMembership.user_id,
                                              CourseMembership.role)).all()),
                sorted(session.execute(select(Invitation.id, Invitation.accepted_at)).all()),
                sorted(session.execute(select(Robot.name, Robot.title, Robot.address, Robot.enabled)).all()),
            )

    return take
