"""A live class goes before the queue only through the access rule: in its leader's booked slot or with an admin's
recorded override, never from a student mid-turn by itself (the rule as create_app composes it, on SQLite and
PostgreSQL)."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import timedelta

import pytest
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from middleware.access.round_robin import AccessPolicy
from middleware.bookings.services import priority_user_id as booking_priority
from middleware.db import make_engine
from middleware.models import Booking, User
from middleware.models.teaching import GuidedSession, Tour
from middleware.teaching.tours import with_guided_priority
from tests.conftest import migrate_to_head
from tests.database.test_round_robin import ROBOT, T0, TURN_S, Lab


class ClassLab(Lab):
    """The round-robin Lab with the composed priority (live classes over bookings) and a student and a tutor."""

    def __init__(self, engine: Engine) -> None:
        super().__init__(engine)
        # A long grace: who stays connected is not the point here, who goes first is.
        self.policy = AccessPolicy(grace_s=3600.0, turn_length_s=lambda _s, _u: TURN_S,
                                   priority_user_id=with_guided_priority(booking_priority))
        with Session(engine) as session, session.begin():
            people = [User(username=name, role=role, password_hash="x")
                      for name, role in (("ann", "student"), ("tess", "tutor"), ("root", "admin"))]
            tour = Tour(slug="t", title="T", steps_json="[]")
            session.add_all([*people, tour])
            session.flush()
            self.ann, self.tess, self.admin = (p.id for p in people)
            self.tour = tour.id

    def start_class(self, at_s: float, override_by: int | None = None) -> None:
        with Session(self.engine) as session, session.begin():
            session.add(GuidedSession(tour_id=self.tour, robot_name=ROBOT, tutor_id=self.tess, step_index=0,
                                      control_user_id=self.tess, version=1, priority_override_by_id=override_by,
                                      started_at=T0 + timedelta(seconds=at_s)))

    def book_for_tutor(self, from_s: float, to_s: float) -> None:
        with Session(self.engine) as session, session.begin():
            session.add(Booking(robot_name=ROBOT, user_id=self.tess, kind="class", checked_in_at=T0,
                                starts_at=T0 + timedelta(seconds=from_s), ends_at=T0 + timedelta(seconds=to_s)))

    def student_driving_then_class(self) -> None:
        """ann drives (alone, no limit); the tutor joins the queue; at 20 s a class starts."""
        self.join(self.ann, at_s=0)
        self.join(self.tess, at_s=10)


@pytest.fixture
def lab(database_url: str) -> Iterator[ClassLab]:
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    yield ClassLab(engine)
    engine.dispose()


def test_a_class_without_a_booking_does_not_take_the_robot_from_a_student_mid_turn(lab: ClassLab) -> None:
    lab.student_driving_then_class()
    lab.start_class(at_s=20)
    state = lab.tick(at_s=20.5)
    assert state.controller_id == lab.ann and state.turn_ends_at is not None  # her turn runs out as usual
    state = lab.tick(at_s=TURN_S + 11)
    assert state.controller_id == lab.tess  # the tutor's turn came in line, not by outranking


def test_a_class_in_its_leaders_booked_slot_goes_first_and_stops_with_the_slot(lab: ClassLab) -> None:
    lab.book_for_tutor(from_s=0, to_s=300)
    lab.student_driving_then_class()
    lab.start_class(at_s=20)
    assert lab.tick(at_s=20.5).controller_id == lab.tess
    after = lab.tick(at_s=301)
    assert after.controller_id == lab.tess and after.turn_ends_at is not None  # a limited turn now: ann waits
    assert lab.tick(at_s=302 + TURN_S).controller_id == lab.ann


def test_an_admins_recorded_override_lets_a_class_go_first_without_a_booking(lab: ClassLab) -> None:
    lab.student_driving_then_class()
    lab.start_class(at_s=20, override_by=lab.admin)
    state = lab.tick(at_s=20.5)
    assert state.controller_id == lab.tess and state.turn_ends_at is None


def test_a_booking_of_someone_else_is_not_the_classs_slot(lab: ClassLab) -> None:
    with Session(lab.engine) as session, session.begin():
        session.add(Booking(robot_name=ROBOT, user_id=lab.ann, kind="personal", checked_in_at=T0,
                            starts_at=T0, ends_at=T0 + timedelta(seconds=300)))
    lab.join(lab.tess, at_s=0)
    lab.join(lab.ann, at_s=10)
    lab.start_class(at_s=20)
    assert lab.tick(at_s=20.5).controller_id == lab.ann  # her booking wins over a class without one
