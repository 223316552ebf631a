"""GET and PUT of the current user's named preferences (JSON values)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable

from flask import Blueprint, jsonify, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.api.contract import ANY, about, described, obj
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.models import UserPreference
from middleware.models.accounts import utc_now

blueprint = Blueprint("preferences", __name__)

KEY_PATTERN = re.compile(r"^[a-z][a-z0-9-]{0,63}$")
MAX_VALUE_BYTES = 8 * 1024
# key -> (session, user id) -> why the user cannot change it now, or None (an open delay trial sets the preview)
PreferenceLock = Callable[[Session, int], str | None]
_LOCKS: dict[str, PreferenceLock] = {}


def lock_preference(key: str, lock: PreferenceLock) -> None:
    """Makes key's value fixed for a user while lock gives a reason (the composition root adds the locks)."""
    _LOCKS[key] = lock


def _locked_because(key: str) -> str | None:
    lock = _LOCKS.get(key)
    return lock(get_session(), int(current_user.get_id())) if lock is not None else None


def _key(key: str) -> str:
    if not KEY_PATTERN.fullmatch(key):
        raise ApiError(404, "unknown_preference", gettext("Preference names are lowercase words joined by '-'."), "key")
    return key


def _find(key: str) -> UserPreference | None:
    return get_session().scalar(
        select(UserPreference).where(UserPreference.user_id == int(current_user.get_id()), UserPreference.key == key)
    )


@blueprint.get("/api/me/preferences/<key>")
@login_required
@described(answers={200: obj(("value",), value=ANY)})
def read(key: str) -> ResponseReturnValue:
    """The stored value, or null; for a key that may be locked, why it cannot change now (null when it can)."""
    preference = _find(_key(key))
    answer = {"value": json.loads(preference.value_json) if preference else None}
    if key in _LOCKS:
        answer["locked"] = _locked_because(key)
    return jsonify(answer)


@blueprint.put("/api/me/preferences/<key>")
@login_required
@described(
    body=obj(("value",), value=about("any JSON value of at most 8 KB")),
    answers={200: obj(("value",), value=ANY)},
    refusals=(409,),
)
def write(key: str) -> ResponseReturnValue:
    """Stores a JSON value of at most 8 KB."""
    name = _key(key)
    locked = _locked_because(name)
    if locked:
        raise ApiError(409, "preference_locked", locked, "value")
    body = request.get_json(silent=True)
    if not isinstance(body, dict) or "value" not in body:
        raise ApiError(400, "invalid_field", gettext("Send a JSON object with a 'value'."), "value")
    try:
        text: str | None = json.dumps(body["value"], separators=(",", ":"), allow_nan=False)
    except ValueError:
        text = None
    if text is None or len(text.encode()) > MAX_VALUE_BYTES:
        raise ApiError(400, "invalid_field", gettext("value must be finite JSON of at most %(max_value_bytes)s "
                                                     "bytes.", max_value_bytes=MAX_VALUE_BYTES), "value")
    session = get_session()
    preference = _find(name)
    if preference is None:
        session.add(UserPreference(user_id=int(current_user.get_id()), key=name, value_json=text))
    else:
        preference.value_json, preference.updated_at = text, utc_now()
    return jsonify({"value": body["value"]})

