"""The logged-in user of each request, without a database read on every request.

Flask-Login loads the user for every request; reading the row each time was a third of a skill activation's
own cost. This process keeps a clean detached copy of each recent user and merges it into the request's
session without SQL (`merge(load=False)`), so the request still gets an ordinary persistent User. Changes made
through the ORM in this process drop the copy at once; changes made by another web process reach this one
within MAX_AGE_S (a new role, at most that late). Whether the login itself is still open is not this copy's
question: the user loader asks session_records first, and disabling an account ends its logins there.
"""

from __future__ import annotations

import threading
import time
import weakref

from sqlalchemy import Engine, event, inspect
from sqlalchemy.orm import Session, make_transient_to_detached

from middleware.models import User

MAX_AGE_S = 5.0

# Per database (tests run several apps in one process; ids repeat across their databases).
_copies: weakref.WeakKeyDictionary[Engine, dict[int, tuple[User, float]]] = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def load_user(session: Session, user_id: int) -> User | None:
    """The active user user_id in session (from the copy when fresh), or None."""
    bind = session.get_bind()
    engine = bind if isinstance(bind, Engine) else bind.engine
    user: User | None
    with _lock:
        cached = _copies.get(engine, {}).get(user_id)
    if cached is not None and time.monotonic() - cached[1] <= MAX_AGE_S:
        user = session.merge(cached[0], load=False)
    else:
        user = session.get(User, user_id)
        if user is not None:
            _remember(engine, user)
    return user if user is not None and user.is_active else None


def forget(user_id: int) -> None:
    """Drops the copy of user_id (the next request reads the row)."""
    with _lock:
        for copies in _copies.values():
            copies.pop(user_id, None)


def _remember(engine: Engine, user: User) -> None:
    columns = {attribute.key: getattr(user, attribute.key) for attribute in inspect(User).column_attrs}
    copy = User(**columns)
    make_transient_to_detached(copy)
    with _lock:
        _copies.setdefault(engine, {})[user.id] = (copy, time.monotonic())


@event.listens_for(User, "after_update")
@event.listens_for(User, "after_delete")
def _row_changed(_mapper, _connection, target: User) -> None:
    forget(target.id)
