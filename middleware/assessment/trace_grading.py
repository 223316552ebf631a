"""Experimental tasks graded from what the robot did: pure functions over a recorded trace and a rubric.

A trace is a list of samples [t_s, gx_m, gy_m, gtheta_rad, ox_m, oy_m, otheta_rad]: the simulator's ground
truth (g*, never shown to the browser) and the odometry (o*) at time t_s since the attempt started.
A rubric is a list of bands [[error_bound, fraction], ...] sorted by bound: the first band whose bound the
error does not exceed gives the fraction of the points; beyond the last band the task scores 0.

Tasks:
- reach_point {x_m, y_m}: the error is the ground-truth distance to the point at the end of the run.
- wall_following {x1_m, y1_m, x2_m, y2_m, distance_m, min_travel_m}: the error is the RMS, over the samples,
  of (distance from the wall's line - distance_m); a run travelling less than min_travel_m scores 0.
- report_pose {}: the student reports (x_m, y_m) read from the localization panel; the error is the distance
  from the ground truth at the moment of the report (the trace sample nearest to it).
- obstacle_zone {obstacles, bounds}: the student marks rectangles on the teleperception grid; the error is
  1 - IoU of the marked cells and the scene's obstacles' cells (obstacle_zone.py; no trace needed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from middleware.assessment import obstacle_zone
from middleware.assessment.grading import ItemResult, parse_number

TASK_KINDS = ("reach_point", "wall_following", "report_pose", obstacle_zone.TASK_KIND)
DEFAULT_RUBRIC = [[0.1, 1.0], [0.2, 0.5], [0.4, 0.25]]
MAX_TRACE_SAMPLES = 20000


@dataclass(frozen=True)
class TaskOutcome:
    """What the grader measured and what it concluded."""

    error_m: float | None
    fraction: float
    feedback: str


def band_fraction(rubric: list[list[float]], error: float) -> float:
    """The fraction of the points the rubric gives to error (0 beyond its last band)."""
    for bound, fraction in sorted(rubric, key=lambda band: band[0]):
        if error <= bound + 1e-12:
            return float(fraction)
    return 0.0


def _distance_to_line(x: float, y: float, x1: float, y1: float, x2: float, y2: float) -> float:
    length = math.hypot(x2 - x1, y2 - y1)
    if length == 0:
        return math.hypot(x - x1, y - y1)
    return abs((x2 - x1) * (y1 - y) - (x1 - x) * (y2 - y1)) / length


def _travel(trace: list[list[float]]) -> float:
    return sum(math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(trace, trace[1:], strict=False))


def measure(task: dict[str, Any], trace: list[list[float]], report: dict[str, Any] | None) -> TaskOutcome:
    """The task's error in metres from the trace (and the student's report), with the rubric's fraction."""
    rubric = task.get("rubric") or DEFAULT_RUBRIC
    if task["kind"] == obstacle_zone.TASK_KIND:
        return _measure_zone(task, report, rubric)
    if not trace:
        return TaskOutcome(None, 0.0, "Nothing was recorded: the robot did not report during the attempt.")
    kind = task["kind"]
    if kind == "reach_point":
        last = trace[-1]
        error = math.hypot(last[1] - float(task["x_m"]), last[2] - float(task["y_m"]))
        what = f"The robot ended {error:.3f} m from ({task['x_m']}, {task['y_m']})."
    elif kind == "wall_following":
        travel = _travel(trace)
        if travel < float(task.get("min_travel_m", 1.0)):
            return TaskOutcome(None, 0.0, f"The robot travelled {travel:.2f} m; the task needs at least "
                                          f"{float(task.get('min_travel_m', 1.0)):.2f} m along the wall.")
        offsets = [_distance_to_line(s[1], s[2], float(task["x1_m"]), float(task["y1_m"]), float(task["x2_m"]),
                                     float(task["y2_m"])) - float(task["distance_m"]) for s in trace]
        error = math.sqrt(sum(o * o for o in offsets) / len(offsets))
        what = f"The RMS distance error to the wall was {error:.3f} m over {travel:.2f} m."
    elif kind == "report_pose":
        x, y = (parse_number((report or {}).get(k)) for k in ("x_m", "y_m"))
        if x is None or y is None:
            return TaskOutcome(None, 0.0, "No pose was reported.")
        at = parse_number((report or {}).get("t_s"))
        sample = trace[-1] if at is None else min(trace, key=lambda s: abs(s[0] - at))
        error = math.hypot(x - sample[1], y - sample[2])
        what = f"The reported pose was {error:.3f} m from the robot's true position."
    else:
        raise ValueError(f"unknown task kind {kind!r}")
    fraction = band_fraction(rubric, error)
    return TaskOutcome(error, fraction, f"{what} Rubric: {int(round(fraction * 100))}% of the points.")


def _measure_zone(task: dict[str, Any], zone: dict[str, Any] | None, rubric: list[list[float]]) -> TaskOutcome:
    if not (zone or {}).get("rects"):
        return TaskOutcome(None, 0.0, "No obstacle zone was marked.")
    iou, precision, recall = obstacle_zone.zone_overlap(task, zone)
    fraction = band_fraction(rubric, 1.0 - iou)
    return TaskOutcome(1.0 - iou, fraction, f"The zone you marked overlaps the obstacles with IoU {iou:.2f} "
                                            f"(precision {precision:.2f}, recall {recall:.2f}). "
                                            f"Rubric: {int(round(fraction * 100))}% of the points.")


def grade_task(task: dict[str, Any], points: float, trace: list[list[float]],
               report: dict[str, Any] | None) -> ItemResult:
    """The experimental task's mark as an item of the attempt ("task")."""
    outcome = measure(task, trace, report)
    topics = tuple(task.get("topics") or ())
    return ItemResult("task", round(points * outcome.fraction, 4), points, outcome.fraction >= 1.0,
                      outcome.feedback, topics)
