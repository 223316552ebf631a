"""Validation of booking requests from the JSON API and the booking form; times become aware UTC."""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, date, datetime, time, timedelta
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.validation import decimal_int, within_calendar

SLOT_MINUTES = 30
MAX_BOOKING = timedelta(hours=4)
KINDS = ("personal", "class")
MAX_ID = 2**31 - 1


@dataclass(frozen=True)
class BookingRequest:
    """A validated request to book one robot, or any robot of a pool (pool_kind), from starts_at to ends_at
    (aware, UTC). For a pool booking robot_name is the robot it was asked from (may be empty)."""

    robot_name: str
    starts_at: datetime
    ends_at: datetime
    kind: str
    course_id: int | None
    pool_kind: str | None = None


def parse_instant(value: object, field: str) -> datetime:
    """An ISO 8601 date-time with a zone ('Z' or an offset), as aware UTC."""
    if not isinstance(value, str) or len(value) > 40:
        raise InvalidField(field, gettext("%(field)s must be an ISO 8601 date and time such as 2026-11-23T09:00:00Z.",
                                          field=field))
    try:
        moment = datetime.fromisoformat(value.strip())
    except ValueError:
        raise InvalidField(field, gettext("%(field)s must be an ISO 8601 date and time such as 2026-11-23T09:00:00Z.",
                                          field=field)) from None
    if moment.tzinfo is None:
        raise InvalidField(field, gettext("%(field)s must say its time zone, e.g. end with 'Z' for UTC.", field=field))
    if not within_calendar(moment):
        raise InvalidField(field, gettext("%(field)s must be a date between the years 1900 and 9000.", field=field))
    return moment.astimezone(UTC)


def parse_optional_id(value: object, field: str) -> int | None:
    """A positive whole number, or None when absent or empty."""
    if value is None or value == "":
        return None
    value = decimal_int(value, 1, MAX_ID)
    if value is None:
        raise InvalidField(field, gettext("%(field)s must be a positive whole number.", field=field))
    return value


def parse_booking_request(data: Mapping[str, object]) -> BookingRequest:
    """A BookingRequest from JSON or form fields; ends_at or duration_min gives the end; pool (a robot kind)
    books any robot of that kind instead of robot_name."""
    pool = data.get("pool")
    if pool in (None, ""):
        pool = None
    elif not isinstance(pool, str) or not pool.strip() or len(pool) > 32:
        raise InvalidField("pool", gettext("pool must name a kind of robot, such as 'lab'."))
    robot_name = data.get("robot_name")
    if pool is not None and robot_name in (None, ""):
        robot_name = ""
    elif not isinstance(robot_name, str) or not robot_name.strip() or len(robot_name) > 32:
        raise InvalidField("robot_name", gettext("robot_name must name one of the lab's robots."))
    starts_at = parse_instant(data.get("starts_at"), "starts_at")
    if data.get("ends_at") not in (None, ""):
        ends_at = parse_instant(data.get("ends_at"), "ends_at")
    else:
        minutes = parse_optional_id(data.get("duration_min"), "duration_min")
        if minutes is None:
            raise InvalidField("ends_at", gettext("Give ends_at (or duration_min) for the booking."))
        ends_at = starts_at + timedelta(minutes=min(minutes, 100_000))
    kind = data.get("kind") or "personal"
    if kind not in KINDS:
        raise InvalidField("kind", gettext("kind must be 'personal' or 'class'."))
    course_id = parse_optional_id(data.get("course_id"), "course_id")
    if kind == "class" and course_id is None:
        raise InvalidField("course_id", gettext("A class booking needs the course it is for (course_id)."))
    return BookingRequest(robot_name.strip(), starts_at, ends_at, str(kind), course_id,
                          pool.strip() if pool is not None else None)


def check_slot_shape(starts_at: datetime, ends_at: datetime, now: datetime) -> None:
    """Refuses bookings off the 30-minute grid, not ending after they start, too long, or in the past."""
    for field, moment in (("starts_at", starts_at), ("ends_at", ends_at)):
        if moment.second or moment.microsecond or moment.minute % SLOT_MINUTES:
            raise InvalidField(field, gettext("%(field)s must be on the %(slot_minutes)s-minute grid (:00 or :30).",
                                              field=field, slot_minutes=SLOT_MINUTES))
    if ends_at <= starts_at:
        raise InvalidField("ends_at", gettext("ends_at must be after starts_at."))
    if ends_at - starts_at > MAX_BOOKING:
        raise InvalidField("ends_at", gettext("A booking may last at most 4 hours."))
    if starts_at < now:
        raise InvalidField("starts_at", gettext("That slot has already started; choose one in the future."))


def parse_time_zone(value: object) -> ZoneInfo:
    """An IANA time zone such as 'Europe/Madrid'; UTC for anything unknown."""
    if isinstance(value, str) and 0 < len(value) <= 64 and ".." not in value:
        try:
            return ZoneInfo(value)
        except (ZoneInfoNotFoundError, ValueError):
            pass
    return ZoneInfo("UTC")


def parse_week(value: object, zone: ZoneInfo, now: datetime) -> date:
    """The Monday of the week given as YYYY-MM-DD (any day of it), or of this week in zone."""
    day = now.astimezone(zone).date()
    if isinstance(value, str) and value:
        with contextlib.suppress(ValueError):
            asked = date.fromisoformat(value)
            day = asked if within_calendar(asked) else day
    return day - timedelta(days=day.weekday())


def local_midnight(day: date, zone: ZoneInfo) -> datetime:
    """Midnight at the start of day in zone, as aware UTC."""
    return datetime.combine(day, time(0), tzinfo=zone).astimezone(UTC)
