"""The environment model: a log-odds occupancy grid of the lab with the echo points it was built from.

Below the skills that build it (mapping), match against it (scan matching) and localize in it (localization).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import SceneSpec
from skill_server.skills.base import TickInput

HIT_LOG_ODDS, FREE_LOG_ODDS, CLAMP_LOG_ODDS = 0.9, -0.35, 6.0
FREE_RANGE_M = 6.0  # beyond this, free space along a beam is not carved (long beams graze too much)


@dataclass(frozen=True)
class PublishedGrid:
    """An immutable copy of the grid for GetMap: percent occupancy per cell, 255 where unknown."""

    resolution_m: float
    origin_x_m: float
    origin_y_m: float
    width_cells: int
    height_cells: int
    cells: bytes  # row-major from (0, 0), x fastest
    scans_integrated: int
    sim_time_s: float


class EnvironmentModel:
    """Log-odds occupancy grid in the lab frame; cells are indexed [ix, iy]."""

    def __init__(self, resolution_m: float = 0.05, half_extent_m: float = 6.0) -> None:
        self.resolution_m = resolution_m
        self.origin_m = -half_extent_m
        self.size = int(round(2 * half_extent_m / resolution_m))
        self.log_odds = np.zeros((self.size, self.size), dtype=np.float32)
        self.scans_integrated = 0
        self.version = 0
        self.surfaces_on_cell_edges = False  # True once a floor plan is drawn in (see add_floor_plan)
        self._explained: np.ndarray | None = None  # cells whose echoes the floor plan explains (see add_floor_plan)
        # Where the laser's echoes fell inside each cell (sums, for their mean) and the direction they were seen
        # from: sub-cell surface points for scan matching and a signed distance field for localization.
        self.hit_sum_m = np.zeros((self.size, self.size, 2))
        self.hit_count = np.zeros((self.size, self.size))
        self.view_sum = np.zeros((self.size, self.size, 2))

    def integrate_laser(self, tick: TickInput, beam_step: int = 2, pose: Pose2D | None = None) -> None:
        """Carves free space along the beams and marks their echoes, at pose (default: the believed pose)."""
        pose = pose or tick.pose
        ranges_m = np.asarray(tick.laser_ranges_m)[::beam_step]
        angles_rad = tick.sensors.laser_angles_rad[::beam_step] + pose.theta_rad
        echoed = ranges_m < tick.sensors.laser.max_range_m - 1e-6
        res = self.resolution_m
        steps = np.arange(res, FREE_RANGE_M, res)
        free_len = np.minimum(ranges_m - res, FREE_RANGE_M)
        along = steps[None, :] < free_len[:, None]
        fx = pose.x_m + steps[None, :] * np.cos(angles_rad)[:, None]
        fy = pose.y_m + steps[None, :] * np.sin(angles_rad)[:, None]
        self._add(fx[along], fy[along], FREE_LOG_ODDS)
        hx = pose.x_m + ranges_m[echoed] * np.cos(angles_rad[echoed])
        hy = pose.y_m + ranges_m[echoed] * np.sin(angles_rad[echoed])
        unexplained = self._unexplained(hx, hy)
        self._add(hx[unexplained], hy[unexplained], HIT_LOG_ODDS)
        self._add_points(hx, hy, -np.cos(angles_rad[echoed]), -np.sin(angles_rad[echoed]))
        np.clip(self.log_odds, -CLAMP_LOG_ODDS, CLAMP_LOG_ODDS, out=self.log_odds)
        self.scans_integrated += 1
        self.version += 1

    def add_floor_plan(self, scene: SceneSpec) -> None:
        """Draws the lab's floor plan (walls and furniture as built) in: obstacles occupied, the floor free."""
        centers = self.origin_m + (np.arange(self.size) + 0.5) * self.resolution_m
        xs, ys = np.meshgrid(centers, centers, indexing="ij")
        # A cell is an obstacle's if its centre lies inside it, so drawn surfaces fall on cell edges (the lab's
        # furniture is laid out on the 5 cm grid); readings put theirs mid-cell instead.
        occupied = np.zeros_like(self.log_odds, dtype=bool)
        for box in scene.boxes:
            c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
            dx, dy = xs - box.center_x_m, ys - box.center_y_m
            occupied |= (np.abs(c * dx + s * dy) <= box.half_x_m) & (np.abs(-s * dx + c * dy) <= box.half_y_m)
        for cylinder in scene.cylinders:
            occupied |= np.hypot(xs - cylinder.center_x_m, ys - cylinder.center_y_m) <= cylinder.radius_m
        floor = (np.abs(xs) <= scene.floor_half_x_m) & (np.abs(ys) <= scene.floor_half_y_m)
        self.log_odds[floor] = np.minimum(self.log_odds[floor], -CLAMP_LOG_ODDS)
        self.log_odds[occupied] = CLAMP_LOG_ODDS
        # An echo off a drawn surface lands in the free cell beside it about half the time (the surface lies on
        # the cell edge); marking those cells thickened every wall by a cell, and localization against the
        # thickened walls was 5-8 cm off in a corner while claiming 2 cm. The plan explains those echoes.
        near = occupied.copy()
        near[1:, :] |= occupied[:-1, :]
        near[:-1, :] |= occupied[1:, :]
        near[:, 1:] |= occupied[:, :-1]
        near[:, :-1] |= occupied[:, 1:]
        self._explained = near if self._explained is None else self._explained | near
        self.surfaces_on_cell_edges = True
        self.version += 1

    def integrate_sonar(self, tick: TickInput, pose: Pose2D | None = None) -> None:
        """Marks each sonar's echo on its axis (a cone is too wide to carve free space reliably)."""
        pose = pose or tick.pose
        ranges_m = np.asarray(tick.sonar_ranges_m)
        mounts = np.asarray(tick.sensors.sonar_mount_rad) + pose.theta_rad
        echoed = ranges_m < min(tick.sensors.sonar_max_range_m - 1e-6, 1.5)  # near echoes are sharp enough
        reach = ranges_m[echoed] + tick.sensors.sonar_mount_radius_m
        self._add(pose.x_m + reach * np.cos(mounts[echoed]), pose.y_m + reach * np.sin(mounts[echoed]),
                  0.3 * HIT_LOG_ODDS)

    def _unexplained(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Which echo points the floor plan does not explain (all of them without a plan)."""
        if self._explained is None:
            return np.ones(xs.shape, dtype=bool)
        ix = np.clip(np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64), 0, self.size - 1)
        iy = np.clip(np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64), 0, self.size - 1)
        return ~self._explained[ix, iy]

    def _add(self, xs: np.ndarray, ys: np.ndarray, amount: float) -> None:
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        flat = np.unique(ix[inside] * self.size + iy[inside])  # each cell once per scan, like a ray caster
        self.log_odds.reshape(-1)[flat] += amount

    def _add_points(self, xs: np.ndarray, ys: np.ndarray, view_x: np.ndarray, view_y: np.ndarray) -> None:
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        ix, iy = ix[inside], iy[inside]
        np.add.at(self.hit_sum_m[:, :, 0], (ix, iy), xs[inside])
        np.add.at(self.hit_sum_m[:, :, 1], (ix, iy), ys[inside])
        np.add.at(self.hit_count, (ix, iy), 1.0)
        np.add.at(self.view_sum[:, :, 0], (ix, iy), view_x[inside])
        np.add.at(self.view_sum[:, :, 1], (ix, iy), view_y[inside])

    def surface_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Occupied cells holding echoes: their indices (n x 2), mean echo point [m] and unit normal toward the free
        side (the mean direction the echoes were seen from)."""
        cells = np.argwhere(self.occupied() & (self.hit_count > 0))
        ix, iy = cells[:, 0], cells[:, 1]
        points = self.hit_sum_m[ix, iy] / self.hit_count[ix, iy][:, None]
        normals = self.view_sum[ix, iy]
        normals = normals / np.maximum(np.linalg.norm(normals, axis=1), 1e-9)[:, None]
        return cells, points, normals

    def occupied(self) -> np.ndarray:
        """Cells more likely occupied than not, by a margin."""
        return self.log_odds > 0.5

    def publish(self, sim_time_s: float) -> PublishedGrid:
        """An immutable copy for readers in other threads."""
        probability = 1.0 / (1.0 + np.exp(-self.log_odds))
        percent = np.round(probability * 100).astype(np.uint8)
        percent[self.log_odds == 0] = 255
        return PublishedGrid(self.resolution_m, self.origin_m, self.origin_m, self.size, self.size,
                             percent.T.tobytes(), self.scans_integrated, sim_time_s)
