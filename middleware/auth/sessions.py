"""The cookie side of a login: what the signed session cookie carries, and the check made on it each request.

The cookie holds Flask-Login's fields and the key of a server-side record (session_records.py); a cookie
whose record has ended (logout, password change or reset, account disabled) or expired is worthless, in
every worker process and from any client that replays it.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime

from flask import current_app, session
from flask_login import login_user

from middleware.auth import session_records
from middleware.auth.session_records import SessionLimits
from middleware.db import get_session
from middleware.models import User

LOGIN_KEY = "_login_key"
RENEWED_AT_KEY = "_renewed_at"


def _limits() -> SessionLimits:
    return SessionLimits(current_app.config["SESSION_LIFETIME"], current_app.config["SESSION_IDLE_TIMEOUT"])


def begin(user: User) -> None:
    """Logs user in on a fresh, permanent session with a new server-side record."""
    session.clear()  # a fresh session on login, so a planted session id is worthless
    login_user(user)
    session.permanent = True
    session[RENEWED_AT_KEY] = int(time.time())
    session[LOGIN_KEY] = session_records.open_session(get_session(), user.id, datetime.now(UTC))


def password_changed(user: User) -> None:
    """This session changed the user's password: every login of the account ended; this one gets a new one."""
    get_session().flush()  # the password's UPDATE ends the account's logins before the new record exists
    session[LOGIN_KEY] = session_records.open_session(get_session(), user.id, datetime.now(UTC))


def end() -> None:
    """Ends this session's login everywhere (logout)."""
    key = session.get(LOGIN_KEY)
    if isinstance(key, str):
        session_records.end_session(get_session(), key, datetime.now(UTC))


def is_live(user_id: int) -> bool:
    """True when this request's cookie belongs to an open login of user_id."""
    return key_is_live(session.get(LOGIN_KEY), user_id)


def key_is_live(key: object, user_id: int) -> bool:
    """True when key (a cookie's login key, read earlier) is an open login of user_id; needs the app's context."""
    if not isinstance(key, str) or len(key) > 128:
        return False
    return session_records.is_open(get_session(), key, user_id, _limits(), datetime.now(UTC))
