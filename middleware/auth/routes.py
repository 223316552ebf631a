"""Login and logout pages."""

from __future__ import annotations

import math
import time
from datetime import UTC, datetime
from urllib.parse import urlsplit

from flask import Blueprint, redirect, render_template, request, session, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext as _  # type: ignore[import-untyped]
from flask_babel import lazy_gettext
from flask_login import current_user, login_required, logout_user

from middleware.auth import sessions
from middleware.auth.services import log_in
from middleware.db import get_session

blueprint = Blueprint("auth", __name__)

WRONG_CREDENTIALS = lazy_gettext("Wrong username or password. Check both and try again.")
DISABLED_ACCOUNT = lazy_gettext("This account is disabled. Ask your tutor or the lab's administrator to enable it "
                                 "again.")
SESSION_RENEW_S = 300


@blueprint.before_app_request
def renew_session_expiry() -> None:
    """A session lasts PERMANENT_SESSION_LIFETIME from the last activity, to within SESSION_RENEW_S."""
    if session.permanent and time.time() - float(session.get(sessions.RENEWED_AT_KEY, 0)) >= SESSION_RENEW_S:
        session[sessions.RENEWED_AT_KEY] = int(time.time())


def wait_in_words(seconds: int) -> str:
    """'1 second', '40 seconds', '3 minutes' (whole minutes, rounded up, from two minutes on)."""
    if seconds < 120:
        return _("1 second") if seconds == 1 else _("%(seconds)s seconds", seconds=seconds)
    return _("%(minutes)s minutes", minutes=math.ceil(seconds / 60))


def safe_next_url(value: str | None) -> str | None:
    """value when it is a path on this site, else None (no open redirects)."""
    if not value:
        return None
    parts = urlsplit(value)
    if parts.scheme or parts.netloc or not value.startswith("/") or value.startswith("//"):
        return None
    return value


@blueprint.get("/login")
def login() -> ResponseReturnValue:
    """The login form."""
    if current_user.is_authenticated:
        return redirect(url_for("lab.index"))
    return render_template("auth/login.html", error=None, username="", next_url=safe_next_url(request.args.get("next")))


@blueprint.post("/login")
def login_submit() -> ResponseReturnValue:
    """Checks the credentials; a failure re-shows the form with a sentence saying what went wrong."""
    username = request.form.get("username", "")[:128]
    password = request.form.get("password", "")[:256]
    next_url = safe_next_url(request.form.get("next"))
    if not username.strip() or not password:
        error = _("Enter both your username and your password.")
        return render_template("auth/login.html", error=error, username=username, next_url=next_url), 400
    # The attempt is recorded whatever the answer (the throttle counts failures): a 401 is the view's answer,
    # not an error, so the request's unit of work commits it.
    outcome = log_in(get_session(), username, password, request.remote_addr or "unknown", datetime.now(UTC))
    if outcome.blocked_seconds is not None:
        error = _("Too many failed attempts from here; try again in %(wait)s.",
                  wait=wait_in_words(outcome.blocked_seconds))
        return (render_template("auth/login.html", error=error, username=username, next_url=next_url), 429,
                {"Retry-After": str(outcome.blocked_seconds)})
    user = outcome.user
    if user is None:
        error = DISABLED_ACCOUNT if outcome.disabled else WRONG_CREDENTIALS
        return render_template("auth/login.html", error=error, username=username, next_url=next_url), 401
    sessions.begin(user)
    return redirect(next_url or url_for("lab.index"))


@blueprint.post("/logout")
@login_required
def logout() -> ResponseReturnValue:
    """Ends the session everywhere: the cookie, and any copy of it, opens nothing any more."""
    sessions.end()
    logout_user()
    session.clear()
    return redirect(url_for("auth.login"))
