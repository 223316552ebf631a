"""What the exercises API accepts, checked at the edge: code, run modes, reports, and an exercise's definition.

A run's body never carries a grade, a trace or a start: the server places the robot and measures the run itself,
so a body naming one of them is refused (400 naming the field), not silently ignored."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
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
RESERVED_SLUGS = ("new",)  # /exercises/new is the form for a new exercise, so an exercise of that slug had no page
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


@dataclass(frozen=True)
class RubricParameter:
    """One number of a rubric kind as the catalogue's form asks for it: its name in the rubric, its label, its unit
    ("m", "s", "cells", or "" for a share from 0 to 1), a hint, and for an optional one the grader's default."""

    name: str
    label: str
    unit: str
    hint: str
    default: float | None = None  # an optional number: what the grader takes when it is left out

    @property
    def optional(self) -> bool:
        """Whether the rubric may leave it out."""
        return self.default is not None


_GOAL = N_("The goal, in the lab's frame.")
_GOAL_RADIUS = N_("Full points when the robot's centre comes within this distance of the goal (half within twice it).")
_POSE_ERROR = N_("Full points when the reported position is within this distance of where the robot truly was then "
                 "(half within twice it).")
_REGION = N_("The rectangle of floor to sweep, in the lab's frame.")
_LINE = N_("The rectangle the tape's centre draws, in the lab's frame (the lab's line: x from -1.7 to 1.3 m, y from "
           "-0.8 to 0.8 m).")
_WALL = N_("A point of the wall's face, in the lab's frame.")
_CELL = N_("The side of a floor cell.")
# What each rubric kind is called in the form, and the numbers it takes (grading.py measures them), in that order.
RUBRIC_KIND_NAMES = {
    "bump_and_go": N_("Bump and go: distance driven, floor cells visited, time stuck"),
    "wall_following": N_("Follow a wall: RMS error of the distance to it, distance along it"),
    "reach_goal": N_("Reach a goal: the closest distance to it"),
    "cover_room": N_("Sweep a region: the share of it swept"),
    "report_pose": N_("Report the pose: the reported position's error"),
    "follow_line": N_("Follow the line of tape: the share followed, the time off it"),
    "kidnapped": N_("Localize after a kidnapping: the reported position's error, then the goal"),
}
RUBRIC_PARAMETERS: dict[str, tuple[RubricParameter, ...]] = {
    "bump_and_go": (
        RubricParameter("min_travel_m", N_("Distance to drive"), "m",
                N_("Full points when the robot truly drives at least this far (half at half of it).")),
        RubricParameter("min_cells", N_("Floor cells to visit"), "cells",
                N_("Full points when the robot's centre passes through at least this many floor cells.")),
        RubricParameter("stuck_s", N_("Longest time stuck"), "s",
                N_("Full points when the robot never stays in one spot longer than this (half at twice it).")),
        RubricParameter("cell_m", N_("Floor cell size"), "m", _CELL, 0.5),
        RubricParameter("stuck_move_m", N_("Stuck radius"), "m",
                N_("Staying within this distance of one spot counts as stuck."), 0.1),
    ),
    "wall_following": (
        RubricParameter("x1_m", N_("Wall's first point, x"), "m", _WALL),
        RubricParameter("y1_m", N_("Wall's first point, y"), "m", _WALL),
        RubricParameter("x2_m", N_("Wall's second point, x"), "m", _WALL),
        RubricParameter("y2_m", N_("Wall's second point, y"), "m", _WALL),
        RubricParameter("distance_m", N_("Distance to keep from the wall"), "m",
                N_("Between the robot's centre and the wall's face.")),
        RubricParameter("tolerance_m", N_("Allowed RMS error"), "m",
                N_("Full points when the RMS error of that distance stays within this (half within twice it).")),
        RubricParameter("min_travel_m", N_("Distance along the wall"), "m",
                N_("Full points when the robot covers at least this far along the wall (half at half of it).")),
        RubricParameter("settle_s", N_("Settling time"), "s",
                N_("The first seconds are not measured: the robot finds the wall."), 5.0),
    ),
    "reach_goal": (
        RubricParameter("x_m", N_("Goal, x"), "m", _GOAL),
        RubricParameter("y_m", N_("Goal, y"), "m", _GOAL),
        RubricParameter("radius_m", N_("Goal radius"), "m", _GOAL_RADIUS),
    ),
    "cover_room": (
        RubricParameter("x_min_m", N_("Smallest x"), "m", _REGION),
        RubricParameter("x_max_m", N_("Largest x"), "m", _REGION),
        RubricParameter("y_min_m", N_("Smallest y"), "m", _REGION),
        RubricParameter("y_max_m", N_("Largest y"), "m", _REGION),
        RubricParameter("min_coverage", N_("Share to sweep"), "",
                N_("Full points when the robot's body passes over at least this share of the region (0.6 is 60 per "
                   "cent).")),
        RubricParameter("cell_m", N_("Floor cell size"), "m", _CELL, 0.25),
    ),
    "report_pose": (
        RubricParameter("tolerance_m", N_("Allowed position error"), "m", _POSE_ERROR),
    ),
    "follow_line": (
        RubricParameter("x_min_m", N_("Smallest x"), "m", _LINE),
        RubricParameter("x_max_m", N_("Largest x"), "m", _LINE),
        RubricParameter("y_min_m", N_("Smallest y"), "m", _LINE),
        RubricParameter("y_max_m", N_("Largest y"), "m", _LINE),
        RubricParameter("corner_radius_m", N_("Corners' radius"), "m", N_("The lab's line: 0.45 m.")),
        RubricParameter("tolerance_m", N_("Distance that counts as on the line"), "m",
                N_("The robot's centre within this distance of the tape's centre is on the line.")),
        RubricParameter("min_covered", N_("Share of the line to follow"), "",
                N_("Full points when the robot passes along at least this share of the line (0.85 is 85 per cent).")),
        RubricParameter("max_off_s", N_("Longest time off the line"), "s",
                N_("Full points when the robot's centre spends at most this long off the line (half at twice it).")),
    ),
    "kidnapped": (
        RubricParameter("tolerance_m", N_("Allowed position error"), "m", _POSE_ERROR),
        RubricParameter("x_m", N_("Goal, x"), "m", N_("The goal to reach after the report, in the lab's frame.")),
        RubricParameter("y_m", N_("Goal, y"), "m", N_("The goal to reach after the report, in the lab's frame.")),
        RubricParameter("radius_m", N_("Goal radius"), "m", _GOAL_RADIUS),
    ),
}
RUBRIC_NUMBERS = {kind: tuple(p.name for p in numbers if not p.optional) for kind, numbers in RUBRIC_PARAMETERS.items()}
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
        if slug in RESERVED_SLUGS:
            raise InvalidField("slug", gettext("slug %(slug)s is the address of the form for a new exercise; choose "
                                               "another.", slug=slug))
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
