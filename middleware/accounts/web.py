"""The accounts blueprint and what its views share; the views are in one module per thing administered
(user_routes, invitation_routes, robot_routes, throttle_routes). Rules live in services.py, invitations.py and
robot_admin.py, which raise Refused (middleware/errors.py renders it); the request's unit of work commits
(middleware/db.py)."""

from __future__ import annotations

from flask import Blueprint, request, url_for

from middleware.auth.routes import safe_next_url

blueprint = Blueprint("accounts", __name__)


def back_url() -> str:
    """The form's "back" page when it is a path on this site, else the lab's index."""
    return safe_next_url(request.form.get("back")) or url_for("lab.index")

