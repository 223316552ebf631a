"""What a logged-in session carries besides Flask-Login's fields, and the checks made on it.

A session holds a short digest of the password hash it was opened with: changing or resetting a password
changes the digest, so every other session of that account ends at its next request (the one that changed
its own password is given the new digest and stays).
"""

from __future__ import annotations

import hashlib
import time

from flask import session
from flask_login import login_user

from middleware.models import User

PASSWORD_MARK_KEY = "_password_mark"
RENEWED_AT_KEY = "_renewed_at"


def password_mark(user: User) -> str:
    """A digest of the password hash, too short to help anyone guess the password."""
    return hashlib.sha256(user.password_hash.encode()).hexdigest()[:16]


def begin(user: User) -> None:
    """Logs user in on a fresh, permanent session."""
    session.clear()  # a fresh session on login, so a planted session id is worthless
    login_user(user)
    session.permanent = True
    session[RENEWED_AT_KEY] = int(time.time())
    session[PASSWORD_MARK_KEY] = password_mark(user)


def password_changed(user: User) -> None:
    """This session changed the user's password: it stays open; the others end."""
    session[PASSWORD_MARK_KEY] = password_mark(user)


def opened_with_current_password(user: User) -> bool:
    """False when the account's password changed since this session logged in."""
    return session.get(PASSWORD_MARK_KEY) == password_mark(user)
