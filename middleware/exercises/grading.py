"""Exercise rubrics graded from the robot's ground-truth trace: pure functions, the browser's word never counts.

A trace is the robot's own pose log over the run, samples [t_s, gx_m, gy_m, gtheta_rad, ox_m, oy_m, otheta_rad]
(assessment/trace_grading.py's form). A rubric is {"kind": ..., parameters}; each kind turns the trace into
named measurements and each measurement into a fraction (1 when it meets its bar, 0.5 when it meets half of it,
0 below), and the grade is the weighted mean. The kinds:

- bump_and_go {min_travel_m, min_cells, cell_m, stuck_s, stuck_move_m}: the distance driven, the floor cells
  visited, and the longest time spent within stuck_move_m of one spot (pressed against a wall).
- wall_following {x1_m, y1_m, x2_m, y2_m, distance_m, tolerance_m, min_travel_m, settle_s}: the RMS of the
  distance from the wall's line minus distance_m after settle_s, and the distance driven along it.
- reach_goal {x_m, y_m, radius_m}: the closest the robot came to the goal, and when it first got within radius_m.
- cover_room {x_min_m, x_max_m, y_min_m, y_max_m, cell_m, min_coverage}: the share of the region's cells the
  robot's body swept.
- report_pose {tolerance_m}: the distance between the pose the code reported and the truth at that moment.
- follow_line {x_min_m, x_max_m, y_min_m, y_max_m, corner_radius_m, tolerance_m, min_covered, max_off_s}: along
  the scene's line of tape (a rounded rectangle, skill_server/sim/floor_line.py), the share of the line the robot's
  centre passed within tolerance_m of, and the time its centre spent farther than tolerance_m from it.
- kidnapped {tolerance_m, x_m, y_m, radius_m}: report_pose's error of the pose the code reported after the robot
  was carried to an unknown place, and reach_goal's closest distance to the goal after that.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from flask_babel import force_locale, gettext, ngettext  # type: ignore[import-untyped]

from middleware.errors import written_number
from middleware.i18n import N_

RUBRIC_KINDS = ("bump_and_go", "wall_following", "reach_goal", "cover_room", "report_pose", "follow_line", "kidnapped")
LINE_STEP_M = 0.05  # the line is measured at points this far apart
BODY_RADIUS_M = 0.2  # the robot's footprint for the area swept
# Words stored with a result in English and said in the reader's language (feedback_sentence, exercises/services.py).
NO_RUN = N_("The robot recorded no run: nothing to grade.")
REPORTED_POSE_ERROR = N_("reported pose error")
CELLS = N_("cells")  # the one unit that is a word


@dataclass(frozen=True)
class Measurement:
    """One measured quantity of the run, the bar it is held to, and the fraction it earns."""

    name: str
    value: float
    bar: float
    unit: str
    fraction: float
    lower_is_better: bool = False


@dataclass(frozen=True)
class Grade:
    """The run's grade (0..1), each measurement, and a sentence for the student."""

    fraction: float
    measurements: list[Measurement] = field(default_factory=list)
    feedback: str = ""

    def measurements_dict(self) -> list[dict[str, Any]]:
        """The measurements as JSON-ready dicts."""
        return [{"name": m.name, "value": round(m.value, 4), "bar": m.bar, "unit": m.unit,
                 "fraction": m.fraction, "lower_is_better": m.lower_is_better} for m in self.measurements]


def at_least(value: float, bar: float) -> float:
    """1 when value reaches bar, 0.5 when it reaches half of it, else 0."""
    return 1.0 if value >= bar else 0.5 if value >= bar / 2 else 0.0


def at_most(value: float, bar: float) -> float:
    """1 when value stays within bar, 0.5 within twice it, else 0."""
    return 1.0 if value <= bar else 0.5 if value <= 2 * bar else 0.0


def travel_m(trace: list[list[float]]) -> float:
    """The distance the robot truly drove."""
    return sum(math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(trace, trace[1:], strict=False))


def cells_visited(trace: list[list[float]], cell_m: float) -> int:
    """How many floor cells of cell_m the robot's centre passed through."""
    return len({(math.floor(s[1] / cell_m), math.floor(s[2] / cell_m)) for s in trace})


def longest_stuck_s(trace: list[list[float]], move_m: float) -> float:
    """The longest stretch of time the robot stayed within move_m of where the stretch began."""
    longest, begin = 0.0, 0
    for end in range(len(trace)):
        while math.hypot(trace[end][1] - trace[begin][1], trace[end][2] - trace[begin][2]) > move_m:
            begin += 1
        longest = max(longest, trace[end][0] - trace[begin][0])
    return longest


def distance_to_line(x: float, y: float, x1: float, y1: float, x2: float, y2: float) -> float:
    """The distance from (x, y) to the infinite line through (x1, y1) and (x2, y2)."""
    length = math.hypot(x2 - x1, y2 - y1)
    if length == 0:
        return math.hypot(x - x1, y - y1)
    return abs((x2 - x1) * (y1 - y) - (x1 - x) * (y2 - y1)) / length


def swept_share(trace: list[list[float]], p: dict[str, Any]) -> float:
    """The share of the region's cells whose centre came within the body radius of the robot's centre."""
    cell = float(p.get("cell_m", 0.25))
    x_min, x_max, y_min, y_max = (float(p[k]) for k in ("x_min_m", "x_max_m", "y_min_m", "y_max_m"))
    columns, rows = max(1, round((x_max - x_min) / cell)), max(1, round((y_max - y_min) / cell))
    swept: set[tuple[int, int]] = set()
    reach = int(math.ceil(BODY_RADIUS_M / cell))
    for s in trace:
        ci, cj = math.floor((s[1] - x_min) / cell), math.floor((s[2] - y_min) / cell)
        for i in range(ci - reach, ci + reach + 1):
            for j in range(cj - reach, cj + reach + 1):
                if 0 <= i < columns and 0 <= j < rows:
                    cx, cy = x_min + (i + 0.5) * cell, y_min + (j + 0.5) * cell
                    if math.hypot(cx - s[1], cy - s[2]) <= BODY_RADIUS_M:
                        swept.add((i, j))
    return len(swept) / (columns * rows)


def line_distance(x: float, y: float, p: dict[str, Any]) -> float:
    """The distance from (x, y) to the centre of the line of tape, a rounded rectangle (exact: the magnitude of
    its signed distance)."""
    r = float(p["corner_radius_m"])
    x_min, x_max, y_min, y_max = (float(p[k]) for k in ("x_min_m", "x_max_m", "y_min_m", "y_max_m"))
    qx = abs(x - (x_min + x_max) / 2) - ((x_max - x_min) / 2 - r)
    qy = abs(y - (y_min + y_max) / 2) - ((y_max - y_min) / 2 - r)
    return abs(math.hypot(max(qx, 0.0), max(qy, 0.0)) + min(max(qx, qy), 0.0) - r)


def line_points(p: dict[str, Any], step_m: float = LINE_STEP_M) -> list[tuple[float, float]]:
    """Points along the line's centre every step_m (the straight runs, then the corners' quarter circles)."""
    r = float(p["corner_radius_m"])
    x_min, x_max, y_min, y_max = (float(p[k]) for k in ("x_min_m", "x_max_m", "y_min_m", "y_max_m"))
    x0, x1, y0, y1 = x_min + r, x_max - r, y_min + r, y_max - r
    points: list[tuple[float, float]] = []
    for (ax, ay), (bx, by) in (((x0, y_min), (x1, y_min)), ((x_max, y0), (x_max, y1)), ((x1, y_max), (x0, y_max)),
                               ((x_min, y1), (x_min, y0))):
        count = max(1, round(math.hypot(bx - ax, by - ay) / step_m))
        points += [(ax + (bx - ax) * i / count, ay + (by - ay) * i / count) for i in range(count)]
    arc = max(1, round(math.pi / 2 * r / step_m))
    for cx, cy, start in ((x1, y0, -math.pi / 2), (x1, y1, 0.0), (x0, y1, math.pi / 2), (x0, y0, math.pi)):
        points += [(cx + r * math.cos(start + math.pi / 2 * i / arc), cy + r * math.sin(start + math.pi / 2 * i / arc))
                   for i in range(arc)]
    return points


def _segment_distance(px: float, py: float, a: list[float], b: list[float]) -> float:
    dx, dy = b[1] - a[1], b[2] - a[2]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - a[1]) * dx + (py - a[2]) * dy) / length2))
    return math.hypot(px - a[1] - t * dx, py - a[2] - t * dy)


def _follow_line(trace: list[list[float]], p: dict[str, Any]) -> list[Measurement]:
    tolerance = float(p["tolerance_m"])
    on = [line_distance(s[1], s[2], p) <= tolerance for s in trace]
    off_s = sum(b[0] - a[0] for a, b, a_on, b_on in zip(trace, trace[1:], on, on[1:], strict=False)
                if not (a_on and b_on))
    # A point of the line is covered when the robot's centre passed within tolerance of it while on the line.
    legs = [(a, b) for a, b, a_on, b_on in zip(trace, trace[1:], on, on[1:], strict=False) if a_on and b_on]
    points = line_points(p)
    covered = sum(1 for x, y in points
                  if any(_segment_distance(x, y, a, b) <= tolerance for a, b in legs
                         if abs(a[1] - x) <= 1.0 and abs(a[2] - y) <= 1.0))
    share, bar_share, bar_off = covered / len(points), float(p["min_covered"]), float(p["max_off_s"])
    return [Measurement(N_("share of the line followed"), share, bar_share, "", at_least(share, bar_share)),
            Measurement(N_("time off the line"), off_s, bar_off, "s", at_most(off_s, bar_off), True)]


def _kidnapped(trace: list[list[float]], p: dict[str, Any], report: dict[str, Any] | None) -> list[Measurement]:
    located = _report_pose(trace, p, report)
    after = [s for s in trace if s[0] >= float(report.get("t_s", 0.0))] if report else trace
    return located + _reach_goal(after or trace[-1:], p)


def _bump_and_go(trace: list[list[float]], p: dict[str, Any]) -> list[Measurement]:
    travel, cells = travel_m(trace), cells_visited(trace, float(p.get("cell_m", 0.5)))
    stuck = longest_stuck_s(trace, float(p.get("stuck_move_m", 0.1)))
    bar_travel, bar_cells, bar_stuck = float(p["min_travel_m"]), float(p["min_cells"]), float(p["stuck_s"])
    return [Measurement(N_("distance driven"), travel, bar_travel, "m", at_least(travel, bar_travel)),
            Measurement(N_("floor cells visited"), cells, bar_cells, CELLS, at_least(cells, bar_cells)),
            Measurement(N_("longest time stuck"), stuck, bar_stuck, "s", at_most(stuck, bar_stuck), True)]


def _wall_following(trace: list[list[float]], p: dict[str, Any]) -> list[Measurement]:
    settled = [s for s in trace if s[0] >= float(p.get("settle_s", 5.0))] or trace[-1:]
    line = (float(p["x1_m"]), float(p["y1_m"]), float(p["x2_m"]), float(p["y2_m"]))
    offsets = [distance_to_line(s[1], s[2], *line) - float(p["distance_m"]) for s in settled]
    rms = math.sqrt(sum(o * o for o in offsets) / len(offsets))
    # Progress along the wall, not back and forth: the span of the settled samples projected on the wall.
    ux, uy = line[2] - line[0], line[3] - line[1]
    norm = math.hypot(ux, uy) or 1.0
    along = [((s[1] - line[0]) * ux + (s[2] - line[1]) * uy) / norm for s in settled]
    span = max(along) - min(along)
    tolerance, bar_travel = float(p["tolerance_m"]), float(p["min_travel_m"])
    return [Measurement(N_("RMS error of the distance to the wall"), rms, tolerance, "m", at_most(rms, tolerance),
                        True),
            Measurement(N_("distance covered along the wall"), span, bar_travel, "m", at_least(span, bar_travel))]


def _reach_goal(trace: list[list[float]], p: dict[str, Any]) -> list[Measurement]:
    gx, gy, radius = float(p["x_m"]), float(p["y_m"]), float(p["radius_m"])
    distances = [math.hypot(s[1] - gx, s[2] - gy) for s in trace]
    closest = min(distances)
    return [Measurement(N_("closest distance to the goal"), closest, radius, "m", at_most(closest, radius), True)]


def _cover_room(trace: list[list[float]], p: dict[str, Any]) -> list[Measurement]:
    share, bar = swept_share(trace, p), float(p["min_coverage"])
    return [Measurement(N_("share of the room swept"), share, bar, "", at_least(share, bar))]


def _report_pose(trace: list[list[float]], p: dict[str, Any], report: dict[str, Any] | None) -> list[Measurement]:
    tolerance = float(p["tolerance_m"])
    if not report:
        return [Measurement(REPORTED_POSE_ERROR, math.inf, tolerance, "m", 0.0, True)]
    at = float(report.get("t_s", trace[-1][0]))
    sample = min(trace, key=lambda s: abs(s[0] - at))
    error = math.hypot(float(report["x_m"]) - sample[1], float(report["y_m"]) - sample[2])
    return [Measurement(REPORTED_POSE_ERROR, error, tolerance, "m", at_most(error, tolerance), True)]


def grade(rubric: dict[str, Any], trace: list[list[float]], report: dict[str, Any] | None = None) -> Grade:
    """The run's grade from the robot's trace (and, for report_pose, what the code reported)."""
    if len(trace) < 2:
        return Grade(0.0, [], NO_RUN)
    kind = rubric["kind"]
    if kind == "bump_and_go":
        measured = _bump_and_go(trace, rubric)
    elif kind == "wall_following":
        measured = _wall_following(trace, rubric)
    elif kind == "reach_goal":
        measured = _reach_goal(trace, rubric)
    elif kind == "cover_room":
        measured = _cover_room(trace, rubric)
    elif kind == "report_pose":
        measured = _report_pose(trace, rubric, report)
    elif kind == "follow_line":
        measured = _follow_line(trace, rubric)
    elif kind == "kidnapped":
        measured = _kidnapped(trace, rubric, report)
    else:
        raise ValueError(f"unknown rubric kind {kind!r}")
    fraction = round(sum(m.fraction for m in measured) / len(measured), 4)
    with force_locale("en"):  # stored in English, as every grader's feedback; said in the reader's language
        feedback = feedback_sentence(fraction, [{"name": m.name, "value": m.value, "bar": m.bar, "unit": m.unit,
                                                 "fraction": m.fraction} for m in measured])
    return Grade(fraction, measured, feedback)


def feedback_sentence(fraction: float, measurements: Iterable[Mapping[str, Any]]) -> str:
    """The grade's sentence for the student, in the request's language (English outside a request), from its
    measurements as measurements_dict gives them: "72% of the points. distance driven 3.10 m (bar 3 m: 100%); ..."."""
    parts = "; ".join(gettext("%(name)s %(value)s%(unit)s (bar %(bar)s%(bar_unit)s: %(percent)s%%)",
                              name=gettext(m["name"]), value=_shown(m["value"]), unit=_unit(m["unit"], m["value"]),
                              bar=written_number(m["bar"], "g"), bar_unit=_unit(m["unit"], m["bar"]),
                              percent=int(m["fraction"] * 100))
                      for m in measurements)
    return str(gettext("%(percent)s%% of the points. %(parts)s.", percent=int(round(fraction * 100)), parts=parts))


def _unit(unit: str, count: float) -> str:
    """The unit after a number; cells, the one word, agrees with the count ("1 cell", "2 cells")."""
    if unit == CELLS:
        return " " + str(ngettext("cell", "cells", 1 if count == 1 else 2))
    return f" {unit}" if unit else ""


def _shown(value: float) -> str:
    if not math.isfinite(value):
        return str(gettext("none"))
    return written_number(value, ".0f") if float(value).is_integer() else written_number(value, ".2f")
