"""Reading a user's stored preferences from other parts of the middleware (the pages that start from them)."""

from __future__ import annotations

import json

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.models import UserPreference

# The camera panel's picture each user chose, per robot kind: {"<kind>": "video" | "drawn"}.
CAMERA_PICTURE_KEY = "camera-picture"


def stored_value(session: Session, user_id: int, key: str) -> object | None:
    """The JSON value user_id stored under key, or None."""
    text = session.scalar(select(UserPreference.value_json).where(UserPreference.user_id == user_id,
                                                                  UserPreference.key == key))
    return None if text is None else json.loads(text)


def chosen_camera_picture(session: Session, user_id: int, kind: str, pictures: tuple[str, ...]) -> str | None:
    """The picture user_id last chose for robots of kind, if one of pictures (anything else stored is ignored)."""
    choices = stored_value(session, user_id, CAMERA_PICTURE_KEY)
    chosen = choices.get(kind) if isinstance(choices, dict) else None
    return chosen if chosen in pictures else None
