"""Teleperception's evidence grid: sonar cones and laser beams accumulated as log-odds, per sensor and per part.

Not the environment model: nothing here places a reading better than odometry does, nothing is matched or
localized, and the floor plan is never drawn in. A student sees what the readings say from where the robot
believes it stood, drift included. Readings taken while the robot stood (the paper's first part, "without robot
motion") and while it drove (the second) are kept apart, as are the two sensors, so a page can show each layer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.sonar import SonarGeometry
from skill_server.skills.environment_model import PublishedGrid

SENSORS = ("sonar", "laser")
PARTS = ("static", "moving")
LASER_HIT, LASER_FREE = 0.9, -0.35
# A sonar echo says "something on this arc", not where on it: weaker evidence per cell than a laser's.
SONAR_HIT, SONAR_FREE = 0.4, -0.2
CLAMP_LOG_ODDS = 6.0
FREE_RANGE_M = 5.0  # beyond this a beam's free space is not carved (long beams graze too much)
SONAR_RAYS_PER_CONE = 7  # the cone is carved and its arc marked along this many rays
GRID_MARGIN_M = 0.5  # around the scene's floor


@dataclass(frozen=True)
class RangeSensors:
    """Where the ring of sonars and the laser look, in the robot frame."""

    sonars: tuple[SonarGeometry, ...]
    sonar_mount_radius_m: float  # sonar ranges are measured from the body's rim
    laser: LaserSpec


class EvidenceGrid:
    """Log-odds per (sensor, part) layer over the scene's floor; cells are indexed [ix, iy]."""

    def __init__(self, half_x_m: float, half_y_m: float, sensors: RangeSensors, resolution_m: float = 0.1) -> None:
        self.resolution_m = resolution_m
        self.origin_x_m = -half_x_m - GRID_MARGIN_M
        self.origin_y_m = -half_y_m - GRID_MARGIN_M
        self.width = int(math.ceil(2 * (half_x_m + GRID_MARGIN_M) / resolution_m))
        self.height = int(math.ceil(2 * (half_y_m + GRID_MARGIN_M) / resolution_m))
        self.sensors = sensors
        self.layers = {(sensor, part): np.zeros((self.width, self.height), dtype=np.float32)
                       for sensor in SENSORS for part in PARTS}
        laser = sensors.laser
        self._laser_rad = np.linspace(laser.angle_min_rad, laser.angle_max_rad, laser.beam_count)
        self._sonar_mount_rad = np.array([s.mount_angle_rad for s in sensors.sonars])
        self._sonar_offsets_rad = np.array([np.linspace(-s.cone_half_angle_rad, s.cone_half_angle_rad,
                                                        SONAR_RAYS_PER_CONE) for s in sensors.sonars])
        self._sonar_max_m = np.array([s.max_range_m for s in sensors.sonars])

    def clear(self) -> None:
        """Forgets every reading."""
        for layer in self.layers.values():
            layer.fill(0.0)

    def add_laser(self, pose: Pose2D, ranges_m: tuple[float, ...], part: str) -> None:
        """Carves free space along every beam from pose and marks its echo."""
        ranges = np.asarray(ranges_m, dtype=float)
        angles = self._laser_rad + pose.theta_rad
        echoed = ranges < self.sensors.laser.max_range_m - 1e-6
        start_x = np.full(ranges.shape, pose.x_m)
        start_y = np.full(ranges.shape, pose.y_m)
        self._add_rays(self.layers["laser", part], start_x, start_y, angles, ranges, echoed, LASER_HIT, LASER_FREE)

    def add_sonar(self, pose: Pose2D, ranges_m: tuple[float, ...], part: str) -> None:
        """Each cone: free space inside it up to its echo, and the echo's arc across the cone."""
        ranges = np.asarray(ranges_m, dtype=float)
        mounts = self._sonar_mount_rad + pose.theta_rad
        rim = self.sensors.sonar_mount_radius_m
        rays = self._sonar_offsets_rad.shape[1]
        start_x = np.repeat(pose.x_m + rim * np.cos(mounts), rays)
        start_y = np.repeat(pose.y_m + rim * np.sin(mounts), rays)
        angles = (mounts[:, None] + self._sonar_offsets_rad).reshape(-1)
        echoed = np.repeat(ranges < self._sonar_max_m - 1e-6, rays)
        self._add_rays(self.layers["sonar", part], start_x, start_y, angles, np.repeat(ranges, rays), echoed,
                       SONAR_HIT, SONAR_FREE)

    def view(self, sensors: tuple[str, ...] = SENSORS, parts: tuple[str, ...] = PARTS, readings: int = 0,
             sim_time_s: float = 0.0) -> PublishedGrid:
        """The sum of the chosen layers as an immutable grid of percent occupancy (255: no reading touched the cell),
        labelled with the count of readings and the time of the last."""
        total = np.zeros((self.width, self.height), dtype=np.float32)
        for sensor in sensors:
            for part in parts:
                total += self.layers[sensor, part]
        np.clip(total, -CLAMP_LOG_ODDS, CLAMP_LOG_ODDS, out=total)
        percent = np.round(100.0 / (1.0 + np.exp(-total))).astype(np.uint8)
        percent[total == 0] = 255
        return PublishedGrid(self.resolution_m, self.origin_x_m, self.origin_y_m, self.width, self.height,
                             percent.T.tobytes(), readings, sim_time_s)

    def _add_rays(self, layer: np.ndarray, start_x: np.ndarray, start_y: np.ndarray, angles: np.ndarray,
                  ranges: np.ndarray, echoed: np.ndarray, hit: float, free_amount: float) -> None:
        res = self.resolution_m
        steps = np.arange(res / 2, FREE_RANGE_M, res / 2)
        free_len = np.minimum(ranges - res, FREE_RANGE_M)
        along = steps[None, :] < free_len[:, None]
        cos, sin = np.cos(angles), np.sin(angles)
        fx = start_x[:, None] + steps[None, :] * cos[:, None]
        fy = start_y[:, None] + steps[None, :] * sin[:, None]
        # Each cell once per reading, and never both free and hit by one reading: the echo wins. A mask marks the
        # free cells without sorting the thousands of points along the beams.
        free = np.zeros(layer.size, dtype=bool)
        free[self._cells(fx[along], fy[along])] = True
        hit_cells = np.unique(self._cells(start_x[echoed] + ranges[echoed] * cos[echoed],
                                          start_y[echoed] + ranges[echoed] * sin[echoed]))
        free[hit_cells] = False
        flat = layer.reshape(-1)
        flat[free] += free_amount
        flat[hit_cells] += hit
        np.clip(layer, -CLAMP_LOG_ODDS, CLAMP_LOG_ODDS, out=layer)

    def _cells(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        ix = np.floor((xs - self.origin_x_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_y_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.width) & (iy >= 0) & (iy < self.height)
        return ix[inside] * self.height + iy[inside]
