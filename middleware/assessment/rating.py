"""The rating scale (1-5 with labelled ends) that bank questions and survey statements share; pure."""

from __future__ import annotations

from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.validation import decimal_int

LOWEST, HIGHEST = 1, 5
DEFAULT_ENDS = ("Strongly disagree", "Strongly agree")
MAX_END_LABEL = 60


def read_rating(value: object, field: str) -> int:
    """A rating from 1 to 5 (a whole number, or its ASCII digits); InvalidField naming the field otherwise."""
    rating = value if isinstance(value, int) and not isinstance(value, bool) else (
        decimal_int(value, LOWEST, HIGHEST) if isinstance(value, str) else None)
    if rating is None or not LOWEST <= rating <= HIGHEST:
        raise InvalidField(field, gettext("%(field)s: choose a rating from %(lowest)s to %(highest)s.", field=field,
                                          lowest=LOWEST, highest=HIGHEST))
    return rating


def rating_or_none(value: object) -> int | None:
    """The rating a stored answer holds, or None when it holds none (grading never raises)."""
    try:
        return read_rating(value, "rating")
    except InvalidField:
        return None


def _end(value: object, field: str, default: str) -> str:
    if value in (None, ""):
        return default
    if not isinstance(value, str) or not value.strip() or len(value.strip()) > MAX_END_LABEL:
        raise InvalidField(field, gettext("%(field)s must be text of 1 to %(max_end_label)s characters.", field=field,
                                          max_end_label=MAX_END_LABEL))
    return " ".join(value.split())


def read_ends(data: dict[str, Any]) -> dict[str, str]:
    """The labels of the scale's ends (what 1 and 5 mean); the agreement scale's when not given."""
    return {"low_label": _end(data.get("low_label"), "low_label", DEFAULT_ENDS[0]),
            "high_label": _end(data.get("high_label"), "high_label", DEFAULT_ENDS[1])}


def scale(ends: dict[str, Any]) -> list[dict[str, object]]:
    """The five points as a page shows them: the value, and the end's label on the first and last."""
    return [{"value": value, "label": ends.get("low_label") if value == LOWEST else
             ends.get("high_label") if value == HIGHEST else ""} for value in range(LOWEST, HIGHEST + 1)]
