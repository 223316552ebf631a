"""The accounts blueprint and what its views share; the views are in one module per thing administered
(user_routes, invitation_routes, robot_routes, throttle_routes). Rules live in services.py, invitations.py and
robot_admin.py, which raise Refused (middleware/errors.py renders it); the request's unit of work commits
(middleware/db.py)."""

from __future__ import annotations

from datetime import UTC, datetime

from flask import Blueprint, request, url_for

from middleware.auth.routes import safe_next_url
from middleware.errors import ApiError

blueprint = Blueprint("accounts", __name__)


def now() -> datetime:
    """The server's clock."""
    return datetime.now(UTC)


def back_url() -> str:
    """The form's "back" page when it is a path on this site, else the lab's index."""
    return safe_next_url(request.form.get("back")) or url_for("lab.index")


def json_body() -> dict[str, object]:
    """The request's JSON object, or a 400."""
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", "Send a JSON object.", "body")
    return data
