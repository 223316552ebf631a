"""Server-side login sessions: opening, checking and ending them (the cookie side is sessions.py).

The cookie carries a random key; the `login_sessions` row, found by the key's SHA-256, says whether the
login is still open. Every worker reads the same rows, so logout, a password change or reset and disabling
an account end the login in every process. A process keeps each "open" verdict and drops it at once when it ends a
session itself, or when it hears that a login of the user ended in another process (forget_verdicts, on the
ACCOUNTS_TOPIC announcement). While it hears those (PostgreSQL's listener connected) it keeps a verdict
HEARD_RECHECK_S, else RECHECK_S, and never past the login's lifetime or idle end as read: a console's request a
second read the row every time with a verdict of RECHECK_S, two thirds of a request's cost in a class of 50.
A listener that reconnects drops every verdict (what it missed meanwhile). No request state in here.
"""

from __future__ import annotations

import hashlib
import logging
import secrets
import threading
import time
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from sqlalchemy import Connection, Engine, event, inspect, select, update
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session, object_session

from middleware import events
from middleware.models import LoginSession, User
from middleware.models.accounts import as_utc

log = logging.getLogger(__name__)
RECHECK_S = 1.0  # a verdict's lifetime while this process may miss an ended login's announcement
HEARD_RECHECK_S = 60.0  # while it hears them: the announcement drops the verdict at once (within milliseconds);
# the lifetime is a net under that, a read per login per worker a minute (at 15 s, a seventh of a 3-worker class's
# transactions)
# Announced (middleware/events.py) with the user's id when logins of the user end, so every worker's sockets of
# that user check their login at once instead of on their next periodic check.
ACCOUNTS_TOPIC = "accounts"
# last_seen_at is written at most this often per session (a write per request would serialise SQLite).
TOUCH_EVERY = timedelta(minutes=1)

# key hash -> (user id, monotonic time of the check, when the login ends unless used again); only open ones are kept.
_verdicts: dict[str, tuple[int, float, datetime]] = {}
_lock = threading.Lock()


@dataclass(frozen=True)
class SessionLimits:
    """How long a login lasts: at most `lifetime` after it began, and `idle` after its last request."""

    lifetime: timedelta
    idle: timedelta


def _key_hash(key: str) -> str:
    return hashlib.sha256(key.encode()).hexdigest()



def open_session(session: Session, user_id: int, now: datetime) -> str:
    """Records a new login of user_id and returns the key its cookie carries; the caller commits."""
    key = secrets.token_urlsafe(32)
    session.add(LoginSession(key_hash=_key_hash(key), user_id=user_id, created_at=now, last_seen_at=now))
    session.flush()
    return key


def is_open(session: Session, key: str, user_id: int, limits: SessionLimits, now: datetime) -> bool:
    """True when key is user_id's login, not ended, not past its lifetime nor its idle timeout."""
    digest = _key_hash(key)
    with _lock:
        verdict = _verdicts.get(digest)
    if (verdict is not None and verdict[0] == user_id and now < verdict[2]
            and time.monotonic() - verdict[1] <= _verdict_lifetime_s(session)):
        return True
    row = session.scalar(select(LoginSession).where(LoginSession.key_hash == digest))
    if row is None or row.user_id != user_id or row.ended_at is not None:
        return _forget(digest)
    last_seen = as_utc(row.last_seen_at)
    ends_at = as_utc(row.created_at) + limits.lifetime
    if now >= ends_at or now >= last_seen + limits.idle:
        return _forget(digest)
    if now - last_seen >= TOUCH_EVERY:
        _touch(session, digest, now)
        last_seen = now
    with _lock:
        _verdicts[digest] = (user_id, time.monotonic(), min(ends_at, last_seen + limits.idle))
    return True


def _verdict_lifetime_s(session: Session) -> float:
    """How long a verdict holds: HEARD_RECHECK_S while this process hears ended logins announced, else RECHECK_S
    (SQLite's bus reaches no other process; a PostgreSQL listener may be reconnecting)."""
    bind = session.get_bind()
    bus = events.bus_of(bind if isinstance(bind, Engine) else bind.engine)
    return HEARD_RECHECK_S if bus.shared and bus.listening.is_set() else RECHECK_S


def _touch(session: Session, digest: str, now: datetime) -> None:
    """Writes the login's last_seen_at in a transaction of its own, committed at once, before the request writes
    anything: in the request's session the touch held SQLite's write lock until the request ended, so a write of
    the request through another connection (a pool's, a seat's) waited for it the whole busy timeout. Bookkeeping:
    when the database is too busy, the next request touches it again."""
    with Session(session.get_bind()) as own:
        try:
            own.execute(update(LoginSession).where(LoginSession.key_hash == digest).values(last_seen_at=now))
            own.commit()
        except OperationalError:
            log.warning("a login's last-seen time was not written (the database is busy); the next request will")


def end_session(session: Session, key: str, now: datetime) -> None:
    """Ends the login whose cookie carries key (logout); the caller commits."""
    digest = _key_hash(key)
    _forget(digest)
    user_id = session.scalar(select(LoginSession.user_id).where(LoginSession.key_hash == digest,
                                                                 LoginSession.ended_at.is_(None)))
    if user_id is None:
        return
    session.execute(update(LoginSession).where(LoginSession.key_hash == digest, LoginSession.ended_at.is_(None))
                    .values(ended_at=now))
    events.announce(session, ACCOUNTS_TOPIC, str(user_id))


def end_all_sessions(connection: Connection | Session, user_id: int, now: datetime) -> None:
    """Ends every open login of user_id; the caller commits."""
    forget_verdicts(user_id)
    connection.execute(update(LoginSession)
                       .where(LoginSession.user_id == user_id, LoginSession.ended_at.is_(None))
                       .values(ended_at=now))


def forget_verdicts(user_id: int | None) -> None:
    """Drops this process's verdicts on user_id's logins (None: everyone's), so their next check reads the rows:
    another process announced that a login of theirs ended."""
    with _lock:
        for digest in [d for d, (owner, _, _) in _verdicts.items() if user_id is None or owner == user_id]:
            del _verdicts[digest]


def _forget(digest: str) -> bool:
    with _lock:
        _verdicts.pop(digest, None)
    return False


@event.listens_for(User, "after_update")
def _credentials_changed(_mapper, connection: Connection, target: User) -> None:
    """A new password (own change, reset, CLI) or a disabled account ends the account's logins, whichever
    code path made the change; a session that changed its own password is given a fresh one (sessions.py)."""
    state = inspect(target)
    disabled = state.attrs.is_active.history.has_changes() and not target.is_active
    if disabled or state.attrs.password_hash.history.has_changes():
        end_all_sessions(connection, target.id, datetime.now(UTC))
        owner = object_session(target)
        if owner is not None:
            events.announce_in_flush(owner, connection, ACCOUNTS_TOPIC, str(target.id))
