"""A line of tape on the floor and the robot's downward line sensor (issue 32's "follow the line").

The line is one closed path of straight runs and quarter circles (a rounded rectangle), kept as its centre line
sampled every SAMPLE_M; the world paints it as floor marks (straight runs as strips, the curves as a chain of small
squares) and the line sensor reads it from the robot's true pose: a row of reflectance cells across the robot's
front, each 1 over the tape's middle, 0 on bare floor, in between on the tape's edge (a cell sees a spot
CELL_SPOT_M wide), with noise like the other sensors. Pure geometry and numpy: no pybullet here, so the grader
(middleware/exercises/grading.py) can measure a run against the same line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from skill_server.sim.geometry import Pose2D

SAMPLE_M = 0.01  # the centre line's sampling step
CURVE_SQUARE_STEP_M = 0.03  # the curves are painted as squares this far apart along the line
TAPE_RGBA = (0.08, 0.08, 0.09, 1.0)  # black tape on the grey floor
CELL_SPOT_M = 0.012  # the width of floor one reflectance cell sees
NOISE_STD = 0.04  # reflectance noise of each reading


@dataclass(frozen=True)
class LineSensorSpec:
    """A row of reflectance cells ahead_m ahead of the robot's centre, at offsets_m to the left (+) and right (-)."""

    ahead_m: float = 0.16
    offsets_m: tuple[float, ...] = (0.045, 0.0225, 0.0, -0.0225, -0.045)
    noise_std: float = NOISE_STD


@dataclass(frozen=True)
class FloorLine:
    """A closed rounded rectangle of tape: x and y of the straight runs' centre lines, the corners' radius."""

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    corner_radius_m: float
    half_width_m: float = 0.02
    rgba: tuple[float, float, float, float] = TAPE_RGBA
    sensor: LineSensorSpec = field(default_factory=LineSensorSpec)

    def centre_points(self, step_m: float = SAMPLE_M) -> np.ndarray:
        """The centre line as (n, 2) points every step_m, counter-clockwise from the bottom run's start."""
        return centre_points(self, step_m)

    @property
    def length_m(self) -> float:
        """The line's length [m]."""
        r = self.corner_radius_m
        return 2 * (self.x_max_m - self.x_min_m - 2 * r) + 2 * (self.y_max_m - self.y_min_m - 2 * r) + 2 * math.pi * r


def centre_points(line: FloorLine, step_m: float = SAMPLE_M) -> np.ndarray:
    """The rounded rectangle's centre line, counter-clockwise: bottom run east, then each corner and run in turn."""
    r = line.corner_radius_m
    x0, x1, y0, y1 = line.x_min_m + r, line.x_max_m - r, line.y_min_m + r, line.y_max_m - r
    runs = [((x0, line.y_min_m), (x1, line.y_min_m), (x1, y0), -math.pi / 2),
            ((line.x_max_m, y0), (line.x_max_m, y1), (x1, y1), 0.0),
            ((x1, line.y_max_m), (x0, line.y_max_m), (x0, y1), math.pi / 2),
            ((line.x_min_m, y1), (line.x_min_m, y0), (x0, y0), math.pi)]
    points: list[tuple[float, float]] = []
    for (ax, ay), (bx, by), (cx, cy), angle in runs:
        count = max(1, round(math.hypot(bx - ax, by - ay) / step_m))
        points += [(ax + (bx - ax) * i / count, ay + (by - ay) * i / count) for i in range(count)]
        arc = max(1, round(math.pi / 2 * r / step_m))
        points += [(cx + r * math.cos(angle + math.pi / 2 * i / arc), cy + r * math.sin(angle + math.pi / 2 * i / arc))
                   for i in range(arc)]
    return np.array(points)


def paint_patches(line: FloorLine) -> list[tuple[float, float, float, float]]:
    """The tape as axis-aligned rectangles (centre x, centre y, half x, half y): a strip per straight run, a chain
    of squares along each curve (floor marks have no yaw)."""
    r, w = line.corner_radius_m, line.half_width_m
    x0, x1, y0, y1 = line.x_min_m + r, line.x_max_m - r, line.y_min_m + r, line.y_max_m - r
    patches = [((x0 + x1) / 2, line.y_min_m, (x1 - x0) / 2, w), ((x0 + x1) / 2, line.y_max_m, (x1 - x0) / 2, w),
               (line.x_min_m, (y0 + y1) / 2, w, (y1 - y0) / 2), (line.x_max_m, (y0 + y1) / 2, w, (y1 - y0) / 2)]
    count = max(2, math.ceil(math.pi / 2 * r / CURVE_SQUARE_STEP_M))
    for cx, cy, start in ((x1, y0, -math.pi / 2), (x1, y1, 0.0), (x0, y1, math.pi / 2), (x0, y0, math.pi)):
        for i in range(1, count):
            a = start + math.pi / 2 * i / count
            patches.append((cx + r * math.cos(a), cy + r * math.sin(a), w, w))
    return patches


def distances_to_line(line: FloorLine, points: np.ndarray) -> np.ndarray:
    """The distance of each of points (m, 2) from the line's centre [m]: the magnitude of the rounded rectangle's
    signed distance, exact and cheap (the sensor reads it at 20 Hz on every robot of a farm)."""
    r = line.corner_radius_m
    centre = np.array([(line.x_min_m + line.x_max_m) / 2, (line.y_min_m + line.y_max_m) / 2])
    inner = np.array([(line.x_max_m - line.x_min_m) / 2 - r, (line.y_max_m - line.y_min_m) / 2 - r])
    q = np.abs(points - centre) - inner
    outside = np.sqrt((np.maximum(q, 0.0) ** 2).sum(axis=1))
    inside = np.minimum(np.maximum(q[:, 0], q[:, 1]), 0.0)
    return np.abs(outside + inside - r)


class LineSensor:
    """Reads a FloorLine from the robot's true pose; a scene without a line gives no readings."""

    def __init__(self, line: FloorLine | None) -> None:
        self.line = line
        self.spec = line.sensor if line is not None else LineSensorSpec()

    def cell_points(self, pose: Pose2D) -> np.ndarray:
        """Where each cell looks on the floor, in the scene's frame (cells, 2)."""
        c, s = math.cos(pose.theta_rad), math.sin(pose.theta_rad)
        ahead = self.spec.ahead_m
        return np.array([(pose.x_m + ahead * c - o * s, pose.y_m + ahead * s + o * c) for o in self.spec.offsets_m])

    def read(self, pose: Pose2D, rng: np.random.Generator | None) -> tuple[float, ...]:
        """Each cell's reflectance of the tape, 0..1 (1: the tape fills its spot), left to right."""
        if self.line is None:
            return ()
        distance = distances_to_line(self.line, self.cell_points(pose))
        inside = (self.line.half_width_m - distance) / CELL_SPOT_M + 0.5  # the share of the spot on the tape
        values = np.clip(inside, 0.0, 1.0)
        if rng is not None and self.spec.noise_std > 0:
            values = np.clip(values + rng.normal(0.0, self.spec.noise_std, values.shape), 0.0, 1.0)
        return tuple(round(float(v), 4) for v in values)
