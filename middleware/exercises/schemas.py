"""What the exercises API accepts, checked at the edge: code, run modes, reports, and an exercise's definition.

A run's body never carries a grade, a trace or a start: the server places the robot and measures the run itself,
so a body naming one of them is refused (400 naming the field), not silently ignored."""

from __future__ import annotations

import math
import re
from datetime import UTC, datetime
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.errors import written_number
from middleware.exercises.grading import RUBRIC_KINDS
from middleware.i18n import N_
from middleware.validation import unstorable, unstorable_place, within_calendar

MAX_CODE_CHARS = 20_000
MAX_STATEMENT_CHARS = 4_000
SLUG_PATTERN = re.compile(r"^[a-z0-9][a-z0-9-]{0,62}$")
MODES = ("practice", "submission")
FORGED_FIELDS = ("grade", "fraction", "trace", "measurements", "start", "started_at", "ended_at", "seed")
MIN_TIME_LIMIT_S, MAX_TIME_LIMIT_S = 5.0, 600.0


def body_object(body: object) -> dict[str, Any]:
    """The request's JSON object, or a 400."""
    if not isinstance(body, dict):
        raise InvalidField("body", gettext("Send a JSON object."))
    return body


def text(value: object, field: str, max_chars: int, what: str) -> str:
    """Stored text of at most max_chars, or a 400 naming field (what: what it must be, marked with N_)."""
    if not isinstance(value, str):
        raise InvalidField(field, gettext("%(field)s must be %(what)s.", field=field, what=gettext(what)))
    if len(value) > max_chars:
        raise InvalidField(field, gettext("%(field)s is at most %(limit)s characters; it has %(length)s.", field=field,
                                          limit=max_chars, length=len(value)))
    if unstorable(value):
        raise InvalidField(field, gettext("%(field)s holds a character that cannot be stored (%(place)s); remove it.",
                                          field=field, place=unstorable_place(value)))
    return value


def code(value: object, field: str = "code") -> str:
    """A student's Python source."""
    return text(value, field, MAX_CODE_CHARS, N_("the program's Python text"))


def run_request(body: object) -> tuple[str, str]:
    """(code, mode) of a run's request; a forged measurement is refused naming its field."""
    data = body_object(body)
    refuse_forged(data)
    mode = data.get("mode", "practice")
    if mode not in MODES:
        raise InvalidField("mode", gettext('mode must be "practice" or "submission".'))
    return code(data.get("code")), str(mode)


def refuse_forged(data: dict[str, Any]) -> None:
    """A 400 for any field only the server may write (the grade, the trace, the start)."""
    for name in FORGED_FIELDS:
        if name in data:
            raise InvalidField(name, gettext("%(name)s is measured by the lab from the robot's own record; a "
                                             "request cannot set it.", name=name))


def finite(value: object, field: str, low: float = -1e6, high: float = 1e6) -> float:
    """A finite number within [low, high], or a 400 naming field."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InvalidField(field, gettext("%(field)s must be a finite number.", field=field))
    if not low <= value <= high:
        raise InvalidField(field, gettext("%(field)s must be between %(low)s and %(high)s; got %(value)s.", field=field,
                                          low=written_number(low, "g"), high=written_number(high, "g"),
                                          value=written_number(value, "g")))
    return float(value)


def finish_request(body: object) -> dict[str, float] | None:
    """The pose the code reported ({"report": {"x_m", "y_m", "t_s"}}), or None; forged measurements refused."""
    data = body_object(body if body is not None else {})
    refuse_forged(data)
    report = data.get("report")
    if report is None:
        return None
    if not isinstance(report, dict):
        raise InvalidField("report", gettext('report must be {"x_m": ..., "y_m": ..., "t_s": ...}.'))
    return {"x_m": finite(report.get("x_m"), "report.x_m"), "y_m": finite(report.get("y_m"), "report.y_m"),
            "t_s": finite(report.get("t_s", 0.0), "report.t_s", 0.0, MAX_TIME_LIMIT_S)}


def _pose(value: object, field: str) -> list[float]:
    if not isinstance(value, list) or len(value) != 3:
        raise InvalidField(field, gettext("%(field)s must be [x_m, y_m, theta_rad].", field=field))
    return [finite(v, f"{field}[{i}]", -50.0, 50.0) for i, v in enumerate(value)]


def _region(value: object, field: str) -> dict[str, list[float]] | None:
    if value is None:
        return None
    if not isinstance(value, dict):
        raise InvalidField(field, gettext('%(field)s must be {"x_m": [low, high], "y_m": [...], "theta_rad": [...]}.',
                                          field=field))
    region = {}
    for key in ("x_m", "y_m", "theta_rad"):
        pair = value.get(key)
        if not isinstance(pair, list) or len(pair) != 2:
            raise InvalidField(f"{field}.{key}", gettext("%(field)s must be [low, high].", field=f"{field}.{key}"))
        low, high = (finite(v, f"{field}.{key}[{i}]", -50.0, 50.0) for i, v in enumerate(pair))
        if low > high:
            raise InvalidField(f"{field}.{key}", gettext("%(field)s: low must not exceed high.",
                                                         field=f"{field}.{key}"))
        region[key] = [low, high]
    return region


RUBRIC_NUMBERS = {
    "bump_and_go": ("min_travel_m", "min_cells", "stuck_s"),
    "wall_following": ("x1_m", "y1_m", "x2_m", "y2_m", "distance_m", "tolerance_m", "min_travel_m"),
    "reach_goal": ("x_m", "y_m", "radius_m"),
    "cover_room": ("x_min_m", "x_max_m", "y_min_m", "y_max_m", "min_coverage"),
    "report_pose": ("tolerance_m",),
    "follow_line": ("x_min_m", "x_max_m", "y_min_m", "y_max_m", "corner_radius_m", "tolerance_m", "min_covered",
                    "max_off_s"),
    "kidnapped": ("tolerance_m", "x_m", "y_m", "radius_m"),
}
OPTIONAL_NUMBERS = ("cell_m", "stuck_move_m", "settle_s")


def _rubric(value: object) -> dict[str, Any]:
    if not isinstance(value, dict) or value.get("kind") not in RUBRIC_KINDS:
        raise InvalidField("rubric.kind", gettext("rubric.kind must be one of %(kinds)s.",
                                                  kinds=", ".join(RUBRIC_KINDS)))
    kind = str(value["kind"])
    rubric: dict[str, Any] = {"kind": kind}
    for name in RUBRIC_NUMBERS[kind]:
        rubric[name] = finite(value.get(name), f"rubric.{name}", -50.0, 1000.0)
    for name in OPTIONAL_NUMBERS:
        if name in value:
            rubric[name] = finite(value[name], f"rubric.{name}", 0.05, 100.0)
    if kind in ("cover_room", "follow_line") and (rubric["x_min_m"] >= rubric["x_max_m"]
                                                 or rubric["y_min_m"] >= rubric["y_max_m"]):
        raise InvalidField("rubric.x_max_m", gettext("The region's maximum must exceed its minimum."))
    if kind == "follow_line" and not 0 <= 2 * rubric["corner_radius_m"] <= min(rubric["x_max_m"] - rubric["x_min_m"],
                                                                             rubric["y_max_m"] - rubric["y_min_m"]):
        raise InvalidField("rubric.corner_radius_m", gettext("The corners' radius must be between 0 and half the "
                                                             "line's shorter side."))
    return rubric


def definition(body: object, slug_required: bool = True) -> dict[str, Any]:
    """An exercise's definition as an admin or tutor writes it (the catalogue's form, catalogue.py)."""
    data = body_object(body)
    result: dict[str, Any] = {}
    if slug_required:
        slug = data.get("slug")
        if not isinstance(slug, str) or not SLUG_PATTERN.fullmatch(slug):
            raise InvalidField("slug", gettext("slug is 1 to 63 lower-case letters, digits and -, starting with a "
                                               "letter or digit."))
        result["slug"] = slug
    result["title"] = text(data.get("title"), "title", 120, N_("the exercise's title"))
    if not result["title"].strip():
        raise InvalidField("title", gettext("%(field)s must not be empty.", field="title"))
    result["statement"] = text(data.get("statement"), "statement", MAX_STATEMENT_CHARS, N_("what the student reads"))
    result["template"] = code(data.get("template"), "template")
    scene = data.get("scene", "lab")
    if not isinstance(scene, str) or not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", scene):
        raise InvalidField("scene", gettext("scene must be a scene's name, such as lab."))
    result["scene"] = scene
    result["rubric"] = _rubric(data.get("rubric"))
    result["start"] = _pose(data.get("start"), "start")
    result["random_starts"] = _region(data.get("random_starts"), "random_starts")
    result["time_limit_s"] = finite(data.get("time_limit_s"), "time_limit_s", MIN_TIME_LIMIT_S, MAX_TIME_LIMIT_S)
    return result


def assignment(body: object) -> tuple[str, datetime, float]:
    """(slug, deadline, points) of an exercise attached to a course as a test."""
    data = body_object(body)
    slug = data.get("slug")
    if not isinstance(slug, str) or not SLUG_PATTERN.fullmatch(slug):
        raise InvalidField("slug", gettext("slug must name an exercise of the catalogue."))
    value = data.get("deadline_at")
    try:
        deadline = datetime.fromisoformat(value.strip().replace("Z", "+00:00")) if isinstance(value, str) else None
    except ValueError:
        deadline = None
    if deadline is None or not within_calendar(deadline):
        raise InvalidField("deadline_at", gettext("%(field)s must be a date and time such as 2026-12-01T18:00:00Z.",
                                                  field="deadline_at"))
    if deadline.tzinfo is None:
        deadline = deadline.replace(tzinfo=UTC)
    return slug, deadline, finite(data.get("points", 10.0), "points", 0.0, 1000.0)
