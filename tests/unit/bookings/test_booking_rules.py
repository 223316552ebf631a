"""Booking rules on SQLite and PostgreSQL: priority and no-shows, check-in, overlaps, allowance, cancellation."""

from __future__ import annotations

import threading
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy.orm import Session, sessionmaker

from middleware.bookings import services
from middleware.bookings.schemas import BookingRequest
from middleware.bookings.services import BookingRefused
from middleware.models import Booking, User
from tests.unit.bookings.conftest import People

GRACE_S = 600
MONDAY_9 = datetime(2031, 3, 3, 9, 0, tzinfo=UTC)  # a Monday, far in the future
BEFORE = MONDAY_9 - timedelta(days=1)


def book(session: Session, user_id: int, start: datetime, minutes: int = 30, robot: str = "lab-1",
         kind: str = "personal", course_id: int | None = None, now: datetime = BEFORE) -> Booking:
    user = session.get(User, user_id)
    booking = services.create_booking(
        session, user, BookingRequest(robot, start, start + timedelta(minutes=minutes), kind, course_id), now)
    session.commit()
    return booking


def count_bookings(session: Session) -> int:
    return session.query(Booking).count()


def test_the_booker_has_priority_during_the_slot_and_nobody_outside_it(factory, people: People) -> None:
    with factory() as session:
        book(session, people.student, MONDAY_9)
        assert services.priority_user_id(session, "lab-1", MONDAY_9 - timedelta(seconds=1), grace_s=GRACE_S) is None
        assert services.priority_user_id(session, "lab-1", MONDAY_9, grace_s=GRACE_S) == people.student
        assert services.priority_user_id(session, "lab-2", MONDAY_9, grace_s=GRACE_S) is None
        assert services.priority_user_id(session, "lab-1", MONDAY_9 + timedelta(minutes=30), grace_s=GRACE_S) is None


def test_a_class_booking_gives_priority_to_the_tutor_who_booked_it(factory, people: People) -> None:
    with factory() as session:
        book(session, people.tutor, MONDAY_9, 60, kind="class", course_id=people.course)
        assert services.priority_user_id(session, "lab-1", MONDAY_9 + timedelta(minutes=45),
                                         grace_s=10**6) == people.tutor


def test_a_no_show_is_released_after_the_grace_period_not_before(factory, people: People) -> None:
    with factory() as session:
        booking = book(session, people.student, MONDAY_9, 60)
        just_before = MONDAY_9 + timedelta(seconds=GRACE_S - 1)
        assert services.priority_user_id(session, "lab-1", just_before, grace_s=GRACE_S) == people.student
        session.commit()
        assert session.get(Booking, booking.id).released_at is None
        just_after = MONDAY_9 + timedelta(seconds=GRACE_S + 1)
        assert services.priority_user_id(session, "lab-1", just_after, grace_s=GRACE_S) is None
        session.commit()
    with factory() as session:
        released = session.get(Booking, booking.id)
        assert released.released_at is not None and released.cancelled_at is None
        # Released stays released: a late arrival does not get priority back.
        services.check_in(session, "lab-1", people.student, just_after + timedelta(seconds=5), grace_s=GRACE_S)
        assert services.priority_user_id(session, "lab-1", just_after + timedelta(seconds=6), grace_s=GRACE_S) is None


def test_checking_in_within_the_grace_period_keeps_the_slot(factory, people: People) -> None:
    with factory() as session:
        booking = book(session, people.student, MONDAY_9, 60)
        services.check_in(session, "lab-1", people.other_student, MONDAY_9 + timedelta(seconds=5), grace_s=GRACE_S)
        assert session.get(Booking, booking.id).checked_in_at is None, "only the holder checks in"
        services.check_in(session, "lab-1", people.student, MONDAY_9 + timedelta(seconds=GRACE_S - 1),
                          grace_s=GRACE_S)
        session.commit()
        assert session.get(Booking, booking.id).checked_in_at is not None
        late = MONDAY_9 + timedelta(minutes=50)
        assert services.priority_user_id(session, "lab-1", late, grace_s=GRACE_S) == people.student


def test_a_check_in_after_the_grace_period_releases_instead(factory, people: People) -> None:
    with factory() as session:
        booking = book(session, people.student, MONDAY_9, 60)
        services.check_in(session, "lab-1", people.student, MONDAY_9 + timedelta(seconds=GRACE_S + 1), grace_s=GRACE_S)
        session.commit()
        assert session.get(Booking, booking.id).released_at is not None
        assert session.get(Booking, booking.id).checked_in_at is None


def test_grace_defaults_to_ten_minutes_outside_an_app() -> None:
    assert services.grace_period_s() == 600


@pytest.mark.parametrize(("offset_min", "minutes"), [(0, 30), (-30, 60), (30, 30), (-60, 240), (15 - 15, 60)])
def test_overlapping_bookings_are_refused_naming_the_field(factory, people: People, offset_min: int,
                                                           minutes: int) -> None:
    with factory() as session:
        book(session, people.student, MONDAY_9, 60)
        with pytest.raises(BookingRefused) as refused:
            book(session, people.admin, MONDAY_9 + timedelta(minutes=offset_min), minutes)
        session.rollback()
        assert refused.value.code == "slot_taken" and refused.value.field == "starts_at"
        assert count_bookings(session) == 1


def test_adjacent_slots_and_other_robots_are_free(factory, people: People) -> None:
    with factory() as session:
        book(session, people.student, MONDAY_9, 60)
        book(session, people.admin, MONDAY_9 + timedelta(minutes=60))
        book(session, people.admin, MONDAY_9 - timedelta(minutes=30))
        book(session, people.admin, MONDAY_9, robot="lab-2")
        assert count_bookings(session) == 4


def test_cancelling_frees_the_slot(factory, people: People) -> None:
    with factory() as session:
        first = book(session, people.student, MONDAY_9, 60)
        services.cancel_booking(session, session.get(User, people.student), first.id, BEFORE)
        session.commit()
        book(session, people.other_student, MONDAY_9, 60)
        assert services.priority_user_id(session, "lab-1", MONDAY_9, grace_s=GRACE_S) == people.other_student


@pytest.mark.parametrize(("start", "minutes", "field"), [
    (MONDAY_9 + timedelta(minutes=15), 30, "starts_at"),
    (MONDAY_9 + timedelta(seconds=1), 30, "starts_at"),
    (MONDAY_9, 45, "ends_at"),
    (MONDAY_9, 270, "ends_at"),
    (BEFORE - timedelta(hours=1), 30, "starts_at"),
])
def test_off_grid_too_long_and_past_bookings_are_refused(factory, people: People, start, minutes, field) -> None:
    with factory() as session:
        with pytest.raises(BookingRefused) as refused:
            book(session, people.admin, start, minutes)
        assert refused.value.field == field and refused.value.status == 400
        session.rollback()
        assert count_bookings(session) == 0


def test_the_weekly_allowance_counts_non_cancelled_bookings_of_the_iso_week(factory, people: People) -> None:
    with factory() as session:
        first = book(session, people.student, MONDAY_9, 60)
        book(session, people.student, MONDAY_9 + timedelta(days=3), 60)  # Thursday: 120 of 120 used
        with pytest.raises(BookingRefused) as refused:
            book(session, people.student, MONDAY_9 + timedelta(days=4), 30)
        session.rollback()
        assert refused.value.code == "allowance_exceeded" and "120" in refused.value.message
        book(session, people.student, MONDAY_9 + timedelta(days=7), 120)  # next Monday: a new week
        services.cancel_booking(session, session.get(User, people.student), first.id, BEFORE)
        session.commit()
        book(session, people.student, MONDAY_9 + timedelta(days=4), 60)  # the cancelled hour is back


def test_the_largest_allowance_of_several_courses_applies(factory, people: People) -> None:
    from middleware.models import CourseMembership

    with factory() as session:
        session.add(CourseMembership(course_id=people.other_course, user_id=people.other_student, role="student"))
        session.commit()
        assert services.student_allowance(session, people.other_student)[0] == 120


def test_class_bookings_need_a_tutor_of_that_course(factory, people: People) -> None:
    with factory() as session:
        for user_id in (people.student, people.other_tutor):
            with pytest.raises(BookingRefused) as refused:
                book(session, user_id, MONDAY_9, 60, kind="class", course_id=people.course)
            session.rollback()
            assert refused.value.status == 403
        book(session, people.tutor, MONDAY_9, 240, kind="class", course_id=people.course)  # no allowance
        book(session, people.admin, MONDAY_9 + timedelta(hours=4), 240, kind="class", course_id=people.other_course)
        assert count_bookings(session) == 2


def test_two_connections_booking_the_same_slot_at_once_one_wins(factory: sessionmaker[Session],
                                                                people: People) -> None:
    """Thread A books and holds its transaction open; B books the same slot meanwhile and must wait and lose."""
    a_inserted, outcomes = threading.Event(), {}

    def first() -> None:
        with factory() as session:
            services.create_booking(session, session.get(User, people.student),
                                    BookingRequest("lab-1", MONDAY_9, MONDAY_9 + timedelta(minutes=30),
                                                   "personal", None), BEFORE)
            a_inserted.set()
            threading.Event().wait(0.5)  # B is now blocked on the robot's row (or not started yet)
            session.commit()
            outcomes["a"] = "booked"

    def second() -> None:
        a_inserted.wait(10)
        with factory() as session:
            try:
                book(session, people.other_student, MONDAY_9, 60)
                outcomes["b"] = "booked"
            except BookingRefused as refused:
                outcomes["b"] = refused.code

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    assert outcomes == {"a": "booked", "b": "slot_taken"}
    with factory() as session:
        assert count_bookings(session) == 1


def test_only_the_booker_a_course_tutor_or_an_admin_may_cancel(factory, people: People) -> None:
    with factory() as session:
        booking = book(session, people.student, MONDAY_9, 30)
        for user_id in (people.other_student, people.other_tutor):
            with pytest.raises(BookingRefused) as refused:
                services.cancel_booking(session, session.get(User, user_id), booking.id, BEFORE)
            assert refused.value.status == 403
        services.cancel_booking(session, session.get(User, people.tutor), booking.id, BEFORE)
        session.commit()
        with pytest.raises(BookingRefused) as refused:
            services.cancel_booking(session, session.get(User, people.admin), booking.id, BEFORE)
        assert refused.value.code == "already_cancelled"
