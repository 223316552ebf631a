"""The "mark the obstacle zone" experimental task (teleperception): the student marks rectangles on the evidence grid
where they believe the obstacles stand; the marks are graded against the scene's obstacles.

The answer (item "zone") is {"rects": [[x_min_m, y_min_m, x_max_m, y_max_m], ...]} in the lab frame, at most
MAX_RECTS. The truth is the scene's obstacle footprints (walls left out: the room's edge is not the exercise),
read from the robot's RobotInfo when the tutor saves the test and stored in the task, which the browser never sees
(review.exam_dict passes only named fields). Both are rasterised on a CELL_M grid over the room (cell centres
inside a shape); the score is the intersection over union of the two cell sets, IoU. The error the rubric bands
grade is 1 - IoU: by default IoU >= 0.5 earns full marks and is a pass, >= 0.3 half, >= 0.15 a quarter. Precision
(marked cells that are obstacle) and recall (obstacle cells marked) are reported beside it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from flask_babel import format_decimal, gettext  # type: ignore[import-untyped]

from middleware.errors import Refused
from middleware.robots.link import RobotUnavailable
from middleware.robots.registry import robot_registry
from protos.telelab.v1 import robot_pb2

TASK_KIND = "obstacle_zone"
ZONE_ITEM = "zone"
MAX_RECTS = 20
CELL_M = 0.05
COORDINATE_LIMIT_M = 50.0
ZONE_RUBRIC = [[0.5, 1.0], [0.7, 0.5], [0.85, 0.25]]  # bounds on 1 - IoU
WALL_PREFIX = "wall"


def is_wall(name: str) -> bool:
    """Whether a scene box or body of this name is a wall (the room's edge), not an obstacle of the exercise."""
    return name.startswith(WALL_PREFIX)


def scene_obstacles(info: robot_pb2.RobotInfo) -> dict[str, Any]:
    """The task's truth from the robot's description: its obstacle boxes and the room's bounds (walls included)."""
    boxes = [{"name": b.name, "center_x_m": b.center_x_m, "center_y_m": b.center_y_m, "half_x_m": b.half_x_m,
              "half_y_m": b.half_y_m, "yaw_rad": b.yaw_rad} for b in info.scene_boxes]
    corners = [corner for box in boxes for corner in _corners(box)]
    xs, ys = [c[0] for c in corners] or [0.0], [c[1] for c in corners] or [0.0]
    return {"obstacles": [b for b in boxes if not is_wall(str(b["name"]))],
            "bounds": [min(xs), min(ys), max(xs), max(ys)]}


def clean_zone(answer: object) -> dict[str, list[list[float]]]:
    """The student's marks, checked: at most MAX_RECTS rectangles of four finite numbers (corners in any order)."""
    rects = answer.get("rects") if isinstance(answer, dict) else None
    if not isinstance(rects, list) or len(rects) > MAX_RECTS:
        raise Refused(400, "invalid_field", gettext("A zone is {rects: [[x_min, y_min, x_max, y_max], ...]} in "
                                                    "metres, at most %(max_rects)s rectangles.", max_rects=MAX_RECTS),
                      ZONE_ITEM)
    cleaned = []
    for index, rect in enumerate(rects):
        if (not isinstance(rect, list) or len(rect) != 4
                or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in rect)
                or not all(math.isfinite(v) and abs(v) <= COORDINATE_LIMIT_M for v in rect)):
            raise Refused(400, "invalid_field", gettext("Rectangle %(number)s must be four numbers within "
                                                        "%(coordinate_limit_m)s m of the origin.", number=index + 1,
                                                        coordinate_limit_m=format_decimal(COORDINATE_LIMIT_M)),
                          f"{ZONE_ITEM}.rects[{index}]")
        x0, y0, x1, y1 = (float(v) for v in rect)
        cleaned.append([min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1)])
    return {"rects": cleaned}


def _corners(box: dict[str, Any]) -> list[tuple[float, float]]:
    c, s = math.cos(box["yaw_rad"]), math.sin(box["yaw_rad"])
    hx, hy = box["half_x_m"], box["half_y_m"]
    return [(box["center_x_m"] + dx * c - dy * s, box["center_y_m"] + dx * s + dy * c)
            for dx, dy in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]


def _cell_centres(bounds: list[float]) -> tuple[np.ndarray, np.ndarray]:
    x0, y0, x1, y1 = bounds
    xs = np.arange(math.floor(x0 / CELL_M), math.ceil(x1 / CELL_M)) * CELL_M + CELL_M / 2
    ys = np.arange(math.floor(y0 / CELL_M), math.ceil(y1 / CELL_M)) * CELL_M + CELL_M / 2
    return np.meshgrid(xs, ys, indexing="ij")


def _truth_mask(obstacles: list[dict[str, Any]], xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    mask = np.zeros(xs.shape, dtype=bool)
    for box in obstacles:
        c, s = math.cos(box["yaw_rad"]), math.sin(box["yaw_rad"])
        dx, dy = xs - box["center_x_m"], ys - box["center_y_m"]
        mask |= (np.abs(c * dx + s * dy) <= box["half_x_m"]) & (np.abs(-s * dx + c * dy) <= box["half_y_m"])
    return mask


def _marked_mask(rects: list[list[float]], xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    mask = np.zeros(xs.shape, dtype=bool)
    for x0, y0, x1, y1 in rects:
        mask |= (xs >= x0) & (xs <= x1) & (ys >= y0) & (ys <= y1)
    return mask


def zone_overlap(task: dict[str, Any], answer: object) -> tuple[float, float, float]:
    """(IoU, precision, recall) of the marked cells against the obstacles' cells, inside the room's bounds."""
    rects = answer.get("rects") if isinstance(answer, dict) else None
    xs, ys = _cell_centres(task["bounds"])
    truth = _truth_mask(task["obstacles"], xs, ys)
    marked = _marked_mask(rects or [], xs, ys)
    both, either = int(np.count_nonzero(truth & marked)), int(np.count_nonzero(truth | marked))
    marked_count, truth_count = int(np.count_nonzero(marked)), int(np.count_nonzero(truth))
    return (both / either if either else 0.0, both / marked_count if marked_count else 0.0,
            both / truth_count if truth_count else 0.0)


def with_scene_truth(task: dict[str, Any] | None, robot_name: str | None) -> dict[str, Any] | None:
    """An obstacle-zone task with its truth read from the robot's scene now; any other task unchanged."""
    if not task or task.get("kind") != TASK_KIND:
        return task
    link = robot_registry().get(robot_name or "")
    if link is None:
        raise Refused(400, "invalid_field", gettext("There is no robot named %(value)s.",
                                                    value=repr(str(robot_name)[:64])), "robot_name")
    try:
        info = link.info(max_age_s=5.0)
    except RobotUnavailable:
        raise Refused(503, "robot_offline", gettext("%(robot_name)s does not answer, and this test is graded "
                                                    "against its scene: start the robot and save again.",
                                                    robot_name=robot_name), "robot_name") from None
    return {**task, **scene_obstacles(info)}
