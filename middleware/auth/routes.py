"""Login and logout pages."""

from __future__ import annotations

from datetime import UTC, datetime
from urllib.parse import urlsplit

from flask import Blueprint, redirect, render_template, request, session, url_for
from flask_login import current_user, login_required, login_user, logout_user

from middleware.auth.services import log_in
from middleware.db import get_session

blueprint = Blueprint("auth", __name__)

WRONG_CREDENTIALS = "Wrong username or password. Check both and try again."


def safe_next_url(value: str | None) -> str | None:
    """value when it is a path on this site, else None (no open redirects)."""
    if not value:
        return None
    parts = urlsplit(value)
    if parts.scheme or parts.netloc or not value.startswith("/") or value.startswith("//"):
        return None
    return value


@blueprint.get("/login")
def login():  # type: ignore[no-untyped-def]
    """The login form."""
    if current_user.is_authenticated:
        return redirect(url_for("lab.index"))
    return render_template("login.html", error=None, username="", next_url=safe_next_url(request.args.get("next")))


@blueprint.post("/login")
def login_submit():  # type: ignore[no-untyped-def]
    """Checks the credentials; a failure re-shows the form with a sentence saying what went wrong."""
    username = request.form.get("username", "")[:128]
    password = request.form.get("password", "")[:256]
    next_url = safe_next_url(request.form.get("next"))
    if not username.strip() or not password:
        error = "Enter both your username and your password."
        return render_template("login.html", error=error, username=username, next_url=next_url), 400
    db_session = get_session()
    outcome = log_in(db_session, username, password, request.remote_addr or "unknown", datetime.now(UTC))
    db_session.commit()
    if outcome.blocked_minutes is not None:
        minutes = outcome.blocked_minutes
        error = f"Too many failed attempts; try again in {minutes} minute{'s' if minutes != 1 else ''}."
        return render_template("login.html", error=error, username=username, next_url=next_url), 429
    user = outcome.user
    if user is None:
        return render_template("login.html", error=WRONG_CREDENTIALS, username=username, next_url=next_url), 401
    session.clear()  # a fresh session on login, so a planted session id is worthless
    login_user(user)
    session.permanent = True
    return redirect(next_url or url_for("lab.index"))


@blueprint.post("/logout")
@login_required
def logout():  # type: ignore[no-untyped-def]
    """Ends the session."""
    logout_user()
    session.clear()
    return redirect(url_for("auth.login"))
