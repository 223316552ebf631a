"""Booking rules: who may book what, allowances, overlaps, cancellation and no-shows. No Flask request state.

Round-robin control (middleware/access) asks `priority_user_id()` who has the robot first right now
and calls `check_in()` when a user connects; both take the session and the time, and the caller commits.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from flask import current_app, has_app_context  # config only, never the request
from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.auth.schemas import InvalidField
from middleware.bookings import pool_slots
from middleware.bookings.schemas import SLOT_MINUTES, BookingRequest, check_slot_shape
from middleware.courses.services import is_course_tutor
from middleware.errors import Refused, written_date, written_number
from middleware.i18n import N_
from middleware.locking import lock_robot_control, lock_user
from middleware.models import Booking, Course, CourseMembership, Robot, User

DEFAULT_GRACE_S = 600.0


class BookingRefused(Refused):
    """A booking action refused (status, stable code, sentence, field: see middleware.errors.Refused)."""


def as_utc(moment: datetime) -> datetime:
    """moment as aware UTC (SQLite hands back naive datetimes that were stored as UTC)."""
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


def grace_period_s(grace_s: float | None = None) -> float:
    """The no-show grace period: grace_s, else the app's TELELAB_BOOKING_GRACE_S, else 10 minutes."""
    if grace_s is not None:
        return grace_s

    if has_app_context():
        return float(current_app.config.get("BOOKING_GRACE_S", DEFAULT_GRACE_S))
    return DEFAULT_GRACE_S


# --- the interface round-robin control uses -------------------------------------------------------


def _active_booking(session: Session, robot_name: str, now: datetime) -> Booking | None:
    return session.scalar(
        select(Booking)
        .where(Booking.robot_name == robot_name, Booking.cancelled_at.is_(None), Booking.released_at.is_(None),
               Booking.starts_at <= now, Booking.ends_at > now)
        .order_by(Booking.starts_at)
        .limit(1)
    )


def _release_if_no_show(booking: Booking, now: datetime, grace_s: float) -> bool:
    """Releases the booking when its holder missed the grace period; True if it is (now) released."""
    if booking.checked_in_at is None and now - as_utc(booking.starts_at) > timedelta(seconds=grace_s):
        booking.released_at = now
        return True
    return False


def priority_user_id(session: Session, robot_name: str, now: datetime, *, grace_s: float | None = None) -> int | None:
    """The user who has the robot first now because of an active booking (the booker; for a class, its tutor).

    None when no booking is active. A booking whose holder has not checked in more than the grace period
    after its start is released here (released_at = now) and None is returned. The caller commits.
    """
    now = as_utc(now)
    booking = _active_booking(session, robot_name, now)
    if booking is None and pool_slots.bind_at_slot_start(session, robot_name, now):
        booking = _active_booking(session, robot_name, now)  # a pool booking whose slot starts took this robot
    if booking is None or _release_if_no_show(booking, now, grace_period_s(grace_s)):
        return None
    return booking.user_id


def robots_with_bookings_now(session: Session, now: datetime) -> set[str]:
    """Every robot priority_user_id may say something of, or release or bind a booking on, now (the access ticker
    leaves the others' queues alone): those with a booking under way, and the robots of a kind whose pool booking's
    slot has started unbound."""
    now = as_utc(now)
    under_way = (Booking.cancelled_at.is_(None), Booking.released_at.is_(None), Booking.starts_at <= now,
                 Booking.ends_at > now)
    named = set(session.scalars(select(Booking.robot_name).where(Booking.robot_name.is_not(None), *under_way)))
    unbound = select(Booking.pool_kind).where(Booking.robot_name.is_(None), *under_way)
    return {name for name in named if name} | set(session.scalars(select(Robot.name).where(Robot.kind.in_(unbound))))


def check_in(session: Session, robot_name: str, user_id: int, now: datetime, *, grace_s: float | None = None) -> None:
    """Records that user_id connected to the robot: sets checked_in_at if they hold the active booking.

    Arriving after the grace period does not rescue a slot: it is released instead. The caller commits.
    """
    now = as_utc(now)
    booking = _active_booking(session, robot_name, now)
    if booking is None or booking.user_id != user_id or booking.checked_in_at is not None:
        return
    if not _release_if_no_show(booking, now, grace_period_s(grace_s)):
        booking.checked_in_at = now


# --- allowances ---------------------------------------------------------------------------------


def iso_week_bounds(moment: datetime) -> tuple[datetime, datetime]:
    """Monday 00:00 UTC of moment's ISO week (in UTC) and the Monday after."""
    day = as_utc(moment).date()
    monday = datetime(day.year, day.month, day.day, tzinfo=UTC) - timedelta(days=day.weekday())
    return monday, monday + timedelta(days=7)


def student_allowance(session: Session, user_id: int) -> tuple[int, int | None]:
    """(minutes per week, course id) of the student's most generous course; (0, None) when not enrolled."""
    row = session.execute(
        select(Course.booking_allowance_min, Course.id)
        .join(CourseMembership, CourseMembership.course_id == Course.id)
        .where(CourseMembership.user_id == user_id, CourseMembership.role == "student")
        .order_by(Course.booking_allowance_min.desc(), Course.id)
        .limit(1)
    ).first()
    return (int(row[0]), int(row[1])) if row else (0, None)


def minutes_booked_in_week(session: Session, user_id: int, moment: datetime) -> int:
    """Minutes of the user's non-cancelled personal bookings starting in moment's ISO week (UTC)."""
    start, end = iso_week_bounds(moment)
    bookings = session.scalars(
        select(Booking).where(Booking.user_id == user_id, Booking.kind == "personal",
                              Booking.cancelled_at.is_(None), Booking.starts_at >= start, Booking.starts_at < end)
    )
    return sum(int((as_utc(b.ends_at) - as_utc(b.starts_at)).total_seconds() // 60) for b in bookings)


@dataclass(frozen=True)
class Unbookable:
    """Why a free slot cannot be booked by someone: a short label for the calendar cell, and a sentence."""

    label: str
    reason: str


def unbookable_weeks(session: Session, actor: User, mondays: Iterable[datetime]) -> dict[datetime, Unbookable]:
    """The ISO weeks (keyed by Monday 00:00 UTC, as `iso_week_bounds` gives) in which actor can book nothing,
    with the reason: a student in no course, in courses that allow no bookings, or with fewer minutes left that
    week than one slot. Tutors and admins have no allowance, so the answer is empty for them."""
    if actor.role != "student":
        return {}
    weeks = sorted(set(mondays))
    allowance, course_id = student_allowance(session, actor.id)
    if course_id is None:
        blocked = Unbookable(N_("not in a course"), gettext("You are not enrolled in any course, so you cannot book a "
                                                        "robot yet; ask your tutor to enrol you."))
        return dict.fromkeys(weeks, blocked)
    if allowance < SLOT_MINUTES:
        blocked = Unbookable(N_("no allowance"), gettext("Your course allows no bookings; ask your tutor if you need "
                                                     "one. You can still use a robot when it is free, in turn with "
                                                     "others."))
        return dict.fromkeys(weeks, blocked)
    out = {}
    for monday in weeks:
        used = minutes_booked_in_week(session, actor.id, monday)
        if allowance - used < SLOT_MINUTES:
            out[monday] = Unbookable(N_("no minutes left"), gettext(
                "You have booked all %(allowance)s minutes your course allows in the week of %(monday)s; cancel a "
                "booking to free some, or choose another week.", allowance=written_number(allowance),
                monday=written_date(monday, "%d %b", "dd MMM")))
    return out


# --- creating and cancelling ------------------------------------------------------------------


def _check_role(session: Session, actor: User, request: BookingRequest) -> int | None:
    """The course id to store on the booking, after checking the actor may make this kind of booking."""
    if request.kind == "class":
        if actor.role == "student":
            raise BookingRefused(403, "forbidden", gettext("Only tutors can book class sessions."), "kind")
        if session.get(Course, request.course_id) is None:
            raise BookingRefused(404, "unknown_course", gettext("There is no course with id %(course_id)s.",
                                                                course_id=request.course_id), "course_id")
        if actor.role == "tutor" and not is_course_tutor(session, actor.id, request.course_id):
            raise BookingRefused(403, "forbidden", gettext("You can book class sessions only for courses you tutor."),
                                 "course_id")
        return request.course_id
    if request.course_id is not None and session.get(Course, request.course_id) is None:
        raise BookingRefused(404, "unknown_course", gettext("There is no course with id %(course_id)s.",
                                                            course_id=request.course_id), "course_id")
    return request.course_id


def _lock_and_check_slot(session: Session, request: BookingRequest) -> str | None:
    """Locks the robot's (and its pool's) control rows, then refuses a slot the robot or the pool cannot give;
    the robot_name to store (None for a pool booking, bound when its slot starts).

    Locks come first: on SQLite the first write of the transaction takes the database's write lock."""
    kind = request.pool_kind or pool_slots.robot_kind(session, request.robot_name)
    robots = pool_slots.lock_kind(session, kind) if kind else []
    if request.pool_kind is not None:
        kind = request.pool_kind
        if not robots:
            raise BookingRefused(404, "unknown_pool", gettext("There is no pool of robots of kind %(kind)s.",
                                                              kind=repr(kind)), "pool")
        if pool_slots.most_held(session, kind, robots, request.starts_at, request.ends_at) >= len(robots):
            free_at = pool_slots.first_free_start(session, kind, robots, request.starts_at, request.ends_at)
            when = (gettext("the first slot as long that fits starts at %(moment)s UTC",
                            moment=free_at.strftime("%Y-%m-%d %H:%M")) if free_at
                    else gettext("no slot as long fits within two weeks"))
            raise BookingRefused(409, "pool_full", gettext("All %(count)s robots of kind %(kind)s are booked for "
                                                           "part of that time; %(when)s.", count=len(robots),
                                                           kind=repr(kind), when=when), "starts_at")
        return None
    if request.robot_name not in robots:
        lock_robot_control(session, request.robot_name)
    clash = session.scalar(
        select(Booking).where(Booking.robot_name == request.robot_name, Booking.cancelled_at.is_(None),
                              Booking.released_at.is_(None), Booking.starts_at < request.ends_at,
                              Booking.ends_at > request.starts_at).limit(1)
    )
    if clash is not None:
        raise BookingRefused(409, "slot_taken",
                             gettext("Someone has already booked part of that time on this robot; choose a free "
                                     "slot."),
                             "starts_at")
    if kind and pool_slots.most_held(session, kind, robots, request.starts_at, request.ends_at) >= len(robots):
        raise BookingRefused(409, "slot_taken", gettext("Bookings of any %(kind)s robot hold every robot of the "
                                                        "kind for part of that time; choose a free slot.", kind=kind),
                             "starts_at")
    return request.robot_name


def create_booking(session: Session, actor: User, request: BookingRequest, now: datetime) -> Booking:
    """Books the slot after every check; overlap and allowance are checked under row locks. Caller commits.

    The robot's robot_control row (and the actor's user row) are locked before anything is read, so two
    worker processes booking the same robot run one after the other and the second sees the first's row.
    """
    try:
        check_slot_shape(request.starts_at, request.ends_at, as_utc(now))
    except InvalidField as invalid:
        raise BookingRefused(400, "invalid_field", invalid.message, invalid.field) from None
    course_id = _check_role(session, actor, request)

    robot_name = _lock_and_check_slot(session, request)
    lock_user(session, actor.id)
    if actor.role == "student":
        allowance, allowance_course = student_allowance(session, actor.id)
        wanted = int((request.ends_at - request.starts_at).total_seconds() // 60)
        used = minutes_booked_in_week(session, actor.id, request.starts_at)
        if used + wanted > allowance:
            raise BookingRefused(
                409, "allowance_exceeded",
                gettext("Your course allows %(allowance)s minutes of bookings a week; you have %(left)s left that "
                        "week and asked for %(wanted)s.", allowance=written_number(allowance),
                        left=written_number(max(0, allowance - used)), wanted=written_number(wanted)), "ends_at")
        course_id = course_id or allowance_course
    booking = Booking(robot_name=robot_name, pool_kind=request.pool_kind, user_id=actor.id, course_id=course_id,
                      kind=request.kind, starts_at=request.starts_at, ends_at=request.ends_at, created_at=as_utc(now))
    session.add(booking)
    session.flush()
    return booking


def may_cancel(session: Session, actor: User, booking: Booking) -> bool:
    """The booker, a tutor of the booking's course, or an admin."""
    return (actor.role == "admin" or booking.user_id == actor.id
            or (actor.role == "tutor" and is_course_tutor(session, actor.id, booking.course_id)))


def cancel_booking(session: Session, actor: User, booking_id: int, now: datetime) -> Booking:
    """Cancels the booking, freeing its slot; the caller commits."""
    booking = session.get(Booking, booking_id)
    if booking is None:
        raise BookingRefused(404, "unknown_booking", gettext("There is no booking with id %(booking_id)s.",
                                                             booking_id=booking_id), "id")
    if not may_cancel(session, actor, booking):
        raise BookingRefused(403, "forbidden", gettext("Only the person who booked, a tutor of the course or an "
                                                       "admin can cancel this booking."), "id")
    if booking.cancelled_at is not None:
        raise BookingRefused(409, "already_cancelled", gettext("This booking is already cancelled."), "id")
    if as_utc(booking.ends_at) <= as_utc(now):
        raise BookingRefused(409, "booking_over", gettext("This booking is over and cannot be cancelled."), "id")
    booking.cancelled_at = as_utc(now)
    return booking


# --- reading --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BookingView:
    """One booking as pages and the API show it."""

    id: int
    robot_name: str | None  # None: a pool booking whose slot has not started (any robot of pool_kind)
    kind: str
    starts_at: datetime
    ends_at: datetime
    status: str  # booked | checked_in | cancelled | released
    mine: bool
    may_cancel: bool
    course_code: str | None
    booked_by: str | None  # shown to tutors and admins only
    pool_kind: str | None = None

    def to_dict(self) -> dict[str, object]:
        """The JSON form, with times as ISO 8601 UTC ('Z')."""
        iso = lambda m: m.strftime("%Y-%m-%dT%H:%M:%SZ")  # noqa: E731
        return {"id": self.id, "robot_name": self.robot_name, "kind": self.kind, "starts_at": iso(self.starts_at),
                "ends_at": iso(self.ends_at), "status": self.status, "mine": self.mine,
                "may_cancel": self.may_cancel, "course_code": self.course_code, "booked_by": self.booked_by,
                "pool": self.pool_kind}


def _status(booking: Booking) -> str:
    if booking.cancelled_at is not None:
        return "cancelled"
    if booking.released_at is not None:
        return "released"
    return "checked_in" if booking.checked_in_at is not None else "booked"


def describe(session: Session, actor: User, bookings: Iterable[Booking], now: datetime) -> list[BookingView]:
    """Views of bookings as actor may see them."""
    rows = list(bookings)
    course_ids = {b.course_id for b in rows if b.course_id is not None}
    codes = dict(session.execute(select(Course.id, Course.code).where(Course.id.in_(course_ids))).all()) \
        if course_ids else {}
    names: dict[int, str] = {}
    if actor.role in ("tutor", "admin") and rows:
        names = dict(session.execute(select(User.id, User.username)
                                     .where(User.id.in_({b.user_id for b in rows}))).all())
    views = []
    for b in rows:
        status = _status(b)
        open_ = status in ("booked", "checked_in") and as_utc(b.ends_at) > as_utc(now)
        views.append(BookingView(
            b.id, b.robot_name, b.kind, as_utc(b.starts_at), as_utc(b.ends_at), status, b.user_id == actor.id,
            open_ and may_cancel(session, actor, b), codes.get(b.course_id) if b.course_id else None,
            names.get(b.user_id), b.pool_kind))
    return views


def robot_bookings(session: Session, robot_name: str, start: datetime, end: datetime) -> list[Booking]:
    """The robot's bookings that hold time between start and end (not cancelled, not released)."""
    return list(session.scalars(
        select(Booking).where(Booking.robot_name == robot_name, Booking.cancelled_at.is_(None),
                              Booking.released_at.is_(None), Booking.starts_at < end, Booking.ends_at > start)
        .order_by(Booking.starts_at)))


def user_bookings(session: Session, user_id: int, since: datetime) -> list[Booking]:
    """The user's bookings ending after since, soonest first, cancelled ones included."""
    return list(session.scalars(
        select(Booking).where(Booking.user_id == user_id, Booking.ends_at > since).order_by(Booking.starts_at)))


def class_sessions_for_student(session: Session, user_id: int, since: datetime) -> list[Booking]:
    """Class sessions of the courses the user is a student in, ending after since."""
    courses = select(CourseMembership.course_id).where(CourseMembership.user_id == user_id)
    return list(session.scalars(
        select(Booking).where(Booking.kind == "class", Booking.course_id.in_(courses), Booking.ends_at > since,
                              Booking.user_id != user_id).order_by(Booking.starts_at)))


def tutored_courses(session: Session, user: User) -> list[Course]:
    """Courses the user may book class sessions for: all for admins, their tutored ones for tutors."""
    if user.role == "admin":
        return list(session.scalars(select(Course).order_by(Course.code)))
    if user.role != "tutor":
        return []
    return list(session.scalars(
        select(Course).join(CourseMembership, CourseMembership.course_id == Course.id)
        .where(CourseMembership.user_id == user.id, CourseMembership.role == "tutor").order_by(Course.code)))
