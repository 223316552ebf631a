"""Login rate limits: failures counted per account and per address over a sliding window.

A blocked login is refused before the password is checked, so guessing costs the attacker time and
the server no hashing. A success erases nothing: the failures from an address keep counting.
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta

from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from middleware.models import LoginFailure

WINDOW = timedelta(minutes=15)
MAX_FAILURES_PER_ACCOUNT = 5
MAX_FAILURES_PER_ADDRESS = 20
KEEP_FAILURES = timedelta(days=1)


def _as_utc(moment: datetime) -> datetime:
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


def _wait(session: Session, column, value: str, limit: int, now: datetime) -> timedelta | None:  # type: ignore[no-untyped-def]
    """How long until fewer than limit failures for value remain in the window; None when not blocked."""
    recent = session.scalars(
        select(LoginFailure.at).where(column == value, LoginFailure.at > now - WINDOW)
        .order_by(LoginFailure.at.desc()).limit(limit)
    ).all()
    if len(recent) < limit:
        return None
    return _as_utc(recent[-1]) + WINDOW - now


def normalise_username(username: str) -> str:
    """The form a username is counted under (so 'Ada ' and 'ada' share one count)."""
    return username.strip().lower()[:128]


def minutes_blocked(session: Session, username: str, address: str, now: datetime) -> int | None:
    """Whole minutes until this account or address may try again, or None when a try is allowed now."""
    waits = [w for w in (
        _wait(session, LoginFailure.username, normalise_username(username), MAX_FAILURES_PER_ACCOUNT, now),
        _wait(session, LoginFailure.address, address[:64], MAX_FAILURES_PER_ADDRESS, now),
    ) if w is not None]
    if not waits:
        return None
    return max(1, math.ceil(max(waits).total_seconds() / 60))


def record_failure(session: Session, username: str, address: str, now: datetime) -> None:
    """Counts one failed login (and forgets failures older than a day); the caller commits."""
    session.add(LoginFailure(username=normalise_username(username), address=address[:64], at=now))
    session.execute(delete(LoginFailure).where(LoginFailure.at < now - KEEP_FAILURES))
