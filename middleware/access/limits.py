"""The low-level settings of a robot (velocity ceilings, watchdog timeout): who may change which, and the request's
shape. No Flask request state; the robot checks the ranges (its own maxima) and names the field it refuses.

Tutors and admins may change every setting. A student may change what a course they study in allows (any one of
their courses allowing it is enough, as with the turn length, the longest of theirs); a student in no course gets
the courses' defaults: the velocity ceilings yes, the watchdog no.
"""

from __future__ import annotations

import math

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.errors import ApiError
from middleware.models import Course, CourseMembership, Role, User

VELOCITY_FIELDS = ("max_linear_mps", "max_angular_radps")
WATCHDOG_FIELD = "watchdog_s"
LIMIT_FIELDS = (*VELOCITY_FIELDS, WATCHDOG_FIELD)
UNITS = {"max_linear_mps": "m/s", "max_angular_radps": "rad/s", WATCHDOG_FIELD: "s"}
SUPERVISOR_ROLES = (Role.TUTOR, Role.ADMIN)


def changeable_fields(session: Session, user: User) -> tuple[str, ...]:
    """The settings user may change on a robot they control, in LIMIT_FIELDS order."""
    if user.role in SUPERVISOR_ROLES:
        return LIMIT_FIELDS
    rows = session.execute(
        select(Course.students_set_velocity, Course.students_set_watchdog)
        .join(CourseMembership, CourseMembership.course_id == Course.id)
        .where(CourseMembership.user_id == user.id, CourseMembership.role == "student")).all()
    velocity = any(row[0] for row in rows) if rows else True
    watchdog = any(row[1] for row in rows) if rows else False
    return (*(VELOCITY_FIELDS if velocity else ()), *((WATCHDOG_FIELD,) if watchdog else ()))


def parse_limits_request(body: object) -> dict[str, float]:
    """The settings asked for ({field: value}, 0 keeps a value): numbers, finite, not negative, known fields."""
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object such as {\"max_linear_mps\": 0.3}."), "body")
    for name in body:
        if name not in LIMIT_FIELDS:
            raise ApiError(400, "invalid_field", gettext("%(name)s is not a setting; the settings are %(settings)s.",
                                                         name=repr(str(name)[:64]),
                                                         settings=", ".join(LIMIT_FIELDS)), str(name)[:64])
    values: dict[str, float] = {}
    for name in LIMIT_FIELDS:
        value = body.get(name)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int | float) or not _finite(value) or value < 0:
            raise ApiError(400, "invalid_field", gettext("%(name)s must be a finite number of %(unit)s, 0 or more (0 "
                                                         "keeps the current value).", name=name, unit=UNITS[name]),
                           name)
        if value:
            values[name] = float(value)
    if not values:
        raise ApiError(400, "invalid_field", gettext("Send at least one of %(settings)s above 0.",
                                                     settings=", ".join(LIMIT_FIELDS)), "body")
    return values


def _finite(value: int | float) -> bool:
    try:
        return math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        return False


def check_permitted(values: dict[str, float], permitted: tuple[str, ...]) -> None:
    """A 403 naming the first setting asked for that the user may not change."""
    for name in values:
        if name not in permitted:
            raise ApiError(403, "not_permitted", gettext("Your course does not let students change %(name)s; ask your "
                                                         "tutor to allow it on the course's page.", name=name), name)
