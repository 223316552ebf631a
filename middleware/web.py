"""What every area's views share and no area owns: the request's JSON body and the server's clock."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from flask import request
from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import ApiError


def now() -> datetime:
    """The server's clock."""
    return datetime.now(UTC)


def json_body() -> dict[str, Any]:
    """The request's JSON object, or a 400."""
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object."), "body")
    return data
