"""Login throttling: a growing delay per (account, address) and per address, never a lock on an account.

Failed logins are rows every worker counts. After `free_failures` failures in WINDOW for one account from one
address, each further try must wait twice as long as the one before (first_delay, doubled up to max_delay);
one address failing across many accounts is slowed the same way after more tries. So a stranger hammering an
account from elsewhere never slows its owner's address. A slowed try is refused before the password is
checked (it costs the attacker time and the server no hashing); a success clears that account's failures
from that address. Admins list the keys being slowed and clear them (`list_throttles`, `clear`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

from sqlalchemy import ColumnElement, and_, delete, func, select
from sqlalchemy.orm import Session

from middleware.models import LoginFailure
from middleware.models.accounts import as_utc

WINDOW = timedelta(hours=1)
KEEP_FAILURES = timedelta(days=1)
MAX_ADDRESS_LENGTH = 64
MAX_USERNAME_LENGTH = 128


@dataclass(frozen=True)
class DelayRule:
    """No delay for the first free_failures failures; then first_delay, doubling each failure, at most max_delay."""

    free_failures: int
    first_delay: timedelta
    max_delay: timedelta

    def delay_after(self, failures: int) -> timedelta:
        """How long a key with this many recent failures waits after its last one."""
        if failures < self.free_failures:
            return timedelta(0)
        return min(self.max_delay, self.first_delay * 2 ** min(failures - self.free_failures, 30))


PER_ACCOUNT_AND_ADDRESS = DelayRule(3, timedelta(seconds=2), timedelta(minutes=15))
PER_ADDRESS = DelayRule(20, timedelta(seconds=2), timedelta(minutes=15))


@dataclass(frozen=True)
class Throttle:
    """A key being slowed: an account tried from an address, or an address (username None) across accounts."""

    username: str | None
    address: str
    failures: int
    last_failure_at: datetime
    blocked_until: datetime | None

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        def stamp(moment: datetime | None) -> str | None:
            return None if moment is None else moment.isoformat().replace("+00:00", "Z")

        return {"username": self.username, "address": self.address, "failures": self.failures,
                "last_failure_at": stamp(self.last_failure_at), "blocked_until": stamp(self.blocked_until)}



def normalise_username(username: str) -> str:
    """The form a username is counted under (so 'Ada ' and 'ada' share one count)."""
    return username.strip().lower()[:MAX_USERNAME_LENGTH]


def normalise_address(address: str) -> str:
    """The form an address is counted under."""
    return address.strip()[:MAX_ADDRESS_LENGTH]


def _blocked_until(failures: int, last: datetime, rule: DelayRule, now: datetime) -> datetime | None:
    until = as_utc(last) + rule.delay_after(failures)
    return until if until > now else None


def _key_blocked_until(session: Session, where: ColumnElement[bool], rule: DelayRule, now: datetime) -> datetime | None:
    failures, last = session.execute(select(func.count(), func.max(LoginFailure.at))
                                     .where(where, LoginFailure.at > now - WINDOW)).one()
    return None if not failures else _blocked_until(failures, last, rule, now)


def seconds_blocked(session: Session, username: str, address: str, now: datetime) -> int | None:
    """Whole seconds until this account may be tried from this address, or None when a try is allowed now."""
    name, place = normalise_username(username), normalise_address(address)
    moments = [m for m in (
        _key_blocked_until(session, and_(LoginFailure.username == name, LoginFailure.address == place),
                           PER_ACCOUNT_AND_ADDRESS, now),
        _key_blocked_until(session, LoginFailure.address == place, PER_ADDRESS, now),
    ) if m is not None]
    if not moments:
        return None
    return max(1, math.ceil((max(moments) - now).total_seconds()))


def record_failure(session: Session, username: str, address: str, now: datetime) -> None:
    """Counts one failed login (and forgets failures older than a day); the caller commits."""
    session.add(LoginFailure(username=normalise_username(username), address=normalise_address(address), at=now))
    session.execute(delete(LoginFailure).where(LoginFailure.at < now - KEEP_FAILURES))


def record_success(session: Session, username: str, address: str) -> None:
    """The account's owner got in from this address: its earlier failures there were theirs; the caller commits."""
    clear(session, address, username)


def list_throttles(session: Session, now: datetime) -> list[Throttle]:
    """The keys slowed now or at their next failure: pairs first, then addresses; the most failures first."""
    recent = LoginFailure.at > now - WINDOW
    pairs = session.execute(
        select(LoginFailure.username, LoginFailure.address, func.count(), func.max(LoginFailure.at)).where(recent)
        .group_by(LoginFailure.username, LoginFailure.address)
        .having(func.count() >= PER_ACCOUNT_AND_ADDRESS.free_failures)).all()
    addresses = session.execute(
        select(LoginFailure.address, func.count(), func.max(LoginFailure.at)).where(recent)
        .group_by(LoginFailure.address).having(func.count() >= PER_ADDRESS.free_failures)).all()
    throttles = [Throttle(name, place, count, as_utc(last),
                          _blocked_until(count, last, PER_ACCOUNT_AND_ADDRESS, now))
                 for name, place, count, last in pairs]
    throttles.sort(key=lambda t: (-t.failures, t.username or "", t.address))
    by_address = [Throttle(None, place, count, as_utc(last), _blocked_until(count, last, PER_ADDRESS, now))
                  for place, count, last in addresses]
    return throttles + sorted(by_address, key=lambda t: (-t.failures, t.address))


def clear(session: Session, address: str, username: str | None = None) -> int:
    """Forgets the failures from address (for username only, when given); returns how many; the caller commits."""
    where = [LoginFailure.address == normalise_address(address)]
    if username is not None:
        where.append(LoginFailure.username == normalise_username(username))
    rows = session.execute(select(func.count()).select_from(LoginFailure).where(*where)).scalar_one()
    session.execute(delete(LoginFailure).where(*where))
    return rows
