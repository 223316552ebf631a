"""The Flask extensions every area shares, created unbound and bound in create_app: CSRF protection and
the login manager (how a session's user is loaded, and what an anonymous visitor is told)."""

from __future__ import annotations

from collections.abc import Callable

from flask import redirect, request, session, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import LoginManager
from flask_wtf.csrf import CSRFProtect

from middleware import db
from middleware.auth import identity, sessions
from middleware.errors import ApiError
from middleware.models import User
from middleware.validation import decimal_int

csrf = CSRFProtect()
login_manager = LoginManager()
login_manager.login_view = "auth.login"
login_manager.login_message = "Log in to open the lab."
login_manager.session_protection = "strong"


@login_manager.user_loader
def _load_user(user_id: str) -> User | None:
    number = decimal_int(user_id, 1)
    if number is None:
        return None
    if not sessions.is_live(number):  # the login was ended or expired, in whichever process
        return None
    return identity.load_user(db.get_session(), number)


def socket_login_check() -> Callable[[int], bool]:
    """Called in the request that opens a socket: how to ask later, outside any request (on the channel loop's
    pool, in the app's context), whether that request's login still holds for user_id."""
    key = session.get(sessions.LOGIN_KEY)

    def still_open(user_id: int) -> bool:
        return sessions.key_is_live(key, user_id) and identity.load_user(db.get_session(), user_id) is not None

    return still_open


@login_manager.unauthorized_handler
def _unauthorized() -> ResponseReturnValue:
    if request.path.startswith("/api/"):
        raise ApiError(401, "not_logged_in", gettext("Log in first; your session may have ended."))
    return redirect(url_for("auth.login", next=request.full_path.rstrip("?")))
