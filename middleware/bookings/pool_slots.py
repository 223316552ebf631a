"""Bookings of "any robot of kind K": how many of a kind's robots are booked at once, the first free slot, and
binding a pool booking to one robot when its slot starts. No Flask request state; the caller commits.

A pool booking holds no robot until its slot starts (robot_name empty). At every moment the bookings that hold a
robot of the kind (named ones on its robots and pool ones) are fewer than its robots, so when the slot starts one
robot is free; binding prefers a robot with no named booking later in the slot.
"""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

from sqlalchemy import or_, select, update
from sqlalchemy.orm import Session

from middleware.access.pools import robots_of_kind
from middleware.locking import lock_robot_control, rows_matched
from middleware.models import Booking, Robot

SEARCH_AHEAD = timedelta(days=14)


def _utc(moment: datetime) -> datetime:
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


def lock_kind(session: Session, kind: str) -> list[str]:
    """Locks the control row of every robot of kind, in name order (so two bookers never deadlock); the names."""
    names = sorted(robots_of_kind(session, kind))
    for name in names:
        lock_robot_control(session, name)
    return names


def robot_kind(session: Session, robot_name: str) -> str | None:
    """The kind of an enabled robot."""
    return session.scalar(select(Robot.kind).where(Robot.name == robot_name, Robot.enabled.is_(True)))


def _holding(session: Session, kind: str, robots: list[str], start: datetime, end: datetime) -> list[Booking]:
    return list(session.scalars(select(Booking).where(
        or_(Booking.pool_kind == kind, Booking.robot_name.in_(robots)), Booking.cancelled_at.is_(None),
        Booking.released_at.is_(None), Booking.starts_at < end, Booking.ends_at > start)))


def most_held(session: Session, kind: str, robots: list[str], start: datetime, end: datetime) -> int:
    """The most robots of kind that bookings hold at one moment between start and end."""
    held = _holding(session, kind, robots, start, end)
    moments = {start} | {_utc(b.starts_at) for b in held if _utc(b.starts_at) > start}
    return max((sum(1 for b in held if _utc(b.starts_at) <= m < _utc(b.ends_at)) for m in moments), default=0)


def first_free_start(session: Session, kind: str, robots: list[str], start: datetime, end: datetime) -> datetime | None:
    """The earliest start at or after start where a slot as long as [start, end) fits the pool; None if none
    within two weeks."""
    length = end - start
    held = _holding(session, kind, robots, start, start + SEARCH_AHEAD + length)
    for candidate in sorted({start} | {_utc(b.ends_at) for b in held if _utc(b.ends_at) > start}):
        if candidate - start > SEARCH_AHEAD:
            break
        if most_held(session, kind, robots, candidate, candidate + length) < len(robots):
            return candidate
    return None


def bind_at_slot_start(session: Session, robot_name: str, now: datetime) -> bool:
    """Binds the oldest started, unbound pool booking of the robot's kind to robot_name, unless another robot of
    the kind is free for the rest of that slot and this one is not (then that robot binds it when it ticks);
    whether one was bound here."""
    kind = robot_kind(session, robot_name)
    if kind is None:
        return False
    pending = session.scalar(select(Booking).where(
        Booking.pool_kind == kind, Booking.robot_name.is_(None), Booking.cancelled_at.is_(None),
        Booking.released_at.is_(None), Booking.starts_at <= now, Booking.ends_at > now)
        .order_by(Booking.starts_at, Booking.id).limit(1))
    if pending is None:
        return False
    robots = robots_of_kind(session, kind)
    busy = {b.robot_name for b in _holding(session, kind, robots, now, _utc(pending.ends_at)) if b.robot_name}
    if robot_name in busy and any(r not in busy for r in robots):
        return False
    return rows_matched(session, update(Booking).where(Booking.id == pending.id, Booking.robot_name.is_(None))
                        .values(robot_name=robot_name)) > 0
