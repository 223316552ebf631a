"""Validation of drive messages from the browser, before anything reaches a robot."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.errors import written_number
from middleware.validation import InvalidInput, parse_message

NAME_PATTERN = re.compile(r"^[a-z][a-z0-9_]{0,63}$")  # skills and their parameters
GOAL_ID_PATTERN = re.compile(r"^[A-Za-z0-9_-]{1,64}$")

MAX_MESSAGE_CHARS = 1024
MAX_SEQUENCE = 2**53  # the largest integer a browser counts exactly


@dataclass(frozen=True)
class DriveLimits:
    """The robot's velocity limits, from its skill server."""

    max_linear_mps: float
    max_angular_radps: float


@dataclass(frozen=True)
class DriveRequest:
    """A validated drive (or stop) command from one socket."""

    sequence: int
    linear_mps: float
    angular_radps: float


def _finite_within(message: dict[str, object], field: str, limit: float, unit: str) -> float:
    value = message.get(field)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InvalidField(field, gettext("%(field)s must be a finite number between %(low)s and %(high)s %(unit)s.",
                                          field=field, low=written_number(-limit, "g"),
                                          high=written_number(limit, "g"), unit=unit))
    if abs(value) > limit:
        raise InvalidField(field, gettext("%(field)s must be between %(low)s and %(high)s %(unit)s; got %(value)s.",
                                          field=field, low=written_number(-limit, "g"),
                                          high=written_number(limit, "g"), unit=unit,
                                          value=written_number(value, "g")))
    return float(value)


def parse_drive_message(raw: object, limits: DriveLimits, previous_sequence: int) -> DriveRequest:
    """A DriveRequest from one WebSocket message, or InvalidField naming what is wrong."""
    try:
        message = parse_message(raw, ("drive", "stop"), MAX_MESSAGE_CHARS)
    except InvalidInput as invalid:  # the drive channel answers InvalidField, as its other checks raise
        raise InvalidField(invalid.field or "message", invalid.message) from None
    kind = message["type"]
    sequence = message.get("sequence")
    if isinstance(sequence, bool) or not isinstance(sequence, int) or not 1 <= sequence <= MAX_SEQUENCE:
        raise InvalidField("sequence", gettext("sequence must be a whole number from 1 to %(high)s.",
                                               high=MAX_SEQUENCE))
    if sequence <= previous_sequence:
        raise InvalidField("sequence", gettext("sequence must be greater than the previous command's (%(previous)s).",
                                               previous=previous_sequence))
    if kind == "stop":
        return DriveRequest(sequence, 0.0, 0.0)
    return DriveRequest(
        sequence,
        _finite_within(message, "linear_mps", limits.max_linear_mps, "m/s"),
        _finite_within(message, "angular_radps", limits.max_angular_radps, "rad/s"),
    )
