"""Scan-to-map matching: a distance field of the occupancy grid, and a Gauss-Newton fit of a scan onto it.

The environment model uses it to correct odometry before integrating each scan (SLAM-lite), so a map built from
readings alone does not inherit the odometry's drift; the likelihood-field localization reads the same field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D, wrap_angle
from skill_server.skills.environment_model import EnvironmentModel

MATCH_INLIER_M = 0.12  # endpoints farther than this from the map are new surfaces (or clutter), not residuals
MATCH_MIN_INLIERS = 25
MATCH_MAX_CORRECTION_M, MATCH_MAX_CORRECTION_RAD = 0.15, math.radians(6.0)


def distance_field(occupied: np.ndarray, cap_cells: int) -> np.ndarray:
    """Approximate distance [cells] from every cell to the nearest occupied one, capped (chamfer passes)."""
    field = np.where(occupied, 0.0, float(cap_cells))
    diagonal = math.sqrt(2.0)
    for _ in range(cap_cells):
        grown = field.copy()
        np.minimum(grown[1:, :], field[:-1, :] + 1, out=grown[1:, :])
        np.minimum(grown[:-1, :], field[1:, :] + 1, out=grown[:-1, :])
        np.minimum(grown[:, 1:], field[:, :-1] + 1, out=grown[:, 1:])
        np.minimum(grown[:, :-1], field[:, 1:] + 1, out=grown[:, :-1])
        np.minimum(grown[1:, 1:], field[:-1, :-1] + diagonal, out=grown[1:, 1:])
        np.minimum(grown[:-1, :-1], field[1:, 1:] + diagonal, out=grown[:-1, :-1])
        np.minimum(grown[1:, :-1], field[:-1, 1:] + diagonal, out=grown[1:, :-1])
        np.minimum(grown[:-1, 1:], field[1:, :-1] + diagonal, out=grown[:-1, 1:])
        field = grown
    return field


def sample_field(field: np.ndarray, origin_m: float, resolution_m: float, xs: np.ndarray,
                 ys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bilinear value of a field [m] between cell centres at world points, and its gradient (d/dx, d/dy)."""
    size = field.shape[0]
    fx = np.clip((xs - origin_m) / resolution_m - 0.5, 0.0, size - 1.001)
    fy = np.clip((ys - origin_m) / resolution_m - 0.5, 0.0, size - 1.001)
    ix, iy = fx.astype(np.int64), fy.astype(np.int64)
    ax, ay = fx - ix, fy - iy
    f00, f01 = field[ix, iy], field[ix, iy + 1]
    f10, f11 = field[ix + 1, iy], field[ix + 1, iy + 1]
    value = (1 - ax) * ((1 - ay) * f00 + ay * f01) + ax * ((1 - ay) * f10 + ay * f11)
    grad_x = ((1 - ay) * (f10 - f00) + ay * (f11 - f01)) / resolution_m
    grad_y = ((1 - ax) * (f01 - f00) + ax * (f11 - f10)) / resolution_m
    return value, grad_x, grad_y


@dataclass(frozen=True)
class MatchResult:
    """A scan's fitted pose, how many endpoints agreed with the map, and their RMS distance to it."""

    pose: Pose2D
    inliers: int
    rms_m: float
    accepted: bool


class ScanMatcher:
    """Fits scans onto the map's surface points (the mean echo in each occupied cell) by robust point-to-line ICP.

    Matching sub-cell points rather than a distance field between cell centres matters: walls built on the 5 cm
    grid put echoes on cell edges, and a field between centres pulls every scan half a cell into the wall, so a map
    built scan after scan would creep.
    """

    def __init__(self, origin_m: float, resolution_m: float, size: int, search_cells: int = 3) -> None:
        self.origin_m, self.resolution_m, self.size = origin_m, resolution_m, size
        self._means = np.full((size, size, 2), np.nan)
        offsets = np.arange(-search_cells, search_cells + 1)
        self._offsets = np.stack(np.meshgrid(offsets, offsets, indexing="ij"), axis=-1).reshape(-1, 2)
        self._version = -1

    @property
    def has_map(self) -> bool:
        """Whether the map holds surface points yet."""
        return bool(np.isfinite(self._means[:, :, 0]).any())

    def update(self, model: EnvironmentModel) -> None:
        """Takes the model's surface points (once per model version)."""
        version = model.version
        if version == self._version:
            return
        self._version = version
        cells, points, _ = model.surface_points()
        self._means.fill(np.nan)
        self._means[cells[:, 0], cells[:, 1]] = points

    def nearest_two(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The two nearest surface points to each world point within the search window (NaN if none), and their
        distances."""
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        cx = np.clip(ix[:, None] + self._offsets[None, :, 0], 0, self.size - 1)
        cy = np.clip(iy[:, None] + self._offsets[None, :, 1], 0, self.size - 1)
        candidates = self._means[cx, cy]  # n x k x 2
        gaps = np.hypot(candidates[..., 0] - xs[:, None], candidates[..., 1] - ys[:, None])
        gaps = np.where(np.isnan(gaps), np.inf, gaps)
        order = np.argpartition(gaps, 1, axis=1)[:, :2]
        rows = np.arange(len(xs))
        first, second = order[:, 0], order[:, 1]
        swap = gaps[rows, second] < gaps[rows, first]
        first, second = np.where(swap, second, first), np.where(swap, first, second)
        return candidates[rows, first], candidates[rows, second], gaps[rows, first], gaps[rows, second]

    def match(self, guess: Pose2D, ranges_m: np.ndarray, angles_rad: np.ndarray, iterations: int = 10) -> MatchResult:
        """The pose near guess that puts the scan's endpoints on the map's surface (point-to-line Gauss-Newton:
        each endpoint against the line through its two nearest surface points)."""
        x, y, theta = guess.x_m, guess.y_m, guess.theta_rad
        inliers, rms = 0, math.inf
        for _ in range(iterations):
            world = theta + angles_rad
            bx, by = ranges_m * np.cos(world), ranges_m * np.sin(world)
            ex, ey = x + bx, y + by
            p1, p2, gap1, gap2 = self.nearest_two(ex, ey)
            tx, ty = p2[:, 0] - p1[:, 0], p2[:, 1] - p1[:, 1]
            length = np.hypot(tx, ty)
            use = (gap1 < MATCH_INLIER_M) & (gap2 < 2.5 * MATCH_INLIER_M) & (length > 0.01)
            inliers = int(np.count_nonzero(use))
            if inliers < MATCH_MIN_INLIERS:
                return MatchResult(guess, inliers, math.inf, False)
            nx, ny = -ty[use] / length[use], tx[use] / length[use]
            px, py = bx[use], by[use]
            residual = nx * (ex[use] - p1[use, 0]) + ny * (ey[use] - p1[use, 1])
            rms = float(np.sqrt(np.mean(residual**2)))
            jac = np.column_stack([nx, ny, -nx * py + ny * px])
            w = 1.0 / (1.0 + (residual / 0.02) ** 2)  # Cauchy: a few stray endpoints cannot drag the fit
            hessian = jac.T @ (jac * w[:, None]) + np.diag([1e-6, 1e-6, 1e-6])
            step = -np.linalg.solve(hessian, jac.T @ (w * residual))
            x, y, theta = x + step[0], y + step[1], theta + step[2]
            if abs(step[0]) + abs(step[1]) < 1e-4 and abs(step[2]) < 1e-4:
                break
        pose = Pose2D(x, y, wrap_angle(theta))
        accepted = (math.hypot(x - guess.x_m, y - guess.y_m) <= MATCH_MAX_CORRECTION_M
                    and abs(wrap_angle(theta - guess.theta_rad)) <= MATCH_MAX_CORRECTION_RAD)
        return MatchResult(pose if accepted else guess, inliers, rms, accepted)


def signed_point_field(model: EnvironmentModel, cap_cells: int) -> np.ndarray:
    """Signed distance [m] from every cell centre to the nearest surface point, negative behind the surface (seen
    from the free side), capped; linear across a surface, so bilinear interpolation puts its zero on the surface."""
    cells, points, normals = model.surface_points()
    size, res, origin = model.size, model.resolution_m, model.origin_m
    best = np.full((size, size), cap_cells * res)
    signed = best.copy()
    for ox in range(-cap_cells, cap_cells + 1):
        for oy in range(-cap_cells, cap_cells + 1):
            if ox * ox + oy * oy > (cap_cells + 1) ** 2:
                continue
            tx, ty = cells[:, 0] + ox, cells[:, 1] + oy
            inside = (tx >= 0) & (tx < size) & (ty >= 0) & (ty < size)
            tx, ty = tx[inside], ty[inside]
            dx = origin + (tx + 0.5) * res - points[inside, 0]
            dy = origin + (ty + 0.5) * res - points[inside, 1]
            gap = np.hypot(dx, dy)
            closer = gap < best[tx, ty]
            tx, ty, gap = tx[closer], ty[closer], gap[closer]
            side = dx[closer] * normals[inside][closer, 0] + dy[closer] * normals[inside][closer, 1]
            best[tx, ty] = gap
            signed[tx, ty] = np.where(side < 0, -gap, gap)
    return signed


def relative(origin: Pose2D, pose: Pose2D) -> Pose2D:
    """pose expressed in origin's frame."""
    dx, dy = pose.x_m - origin.x_m, pose.y_m - origin.y_m
    c, s = math.cos(origin.theta_rad), math.sin(origin.theta_rad)
    return Pose2D(c * dx + s * dy, -s * dx + c * dy, wrap_angle(pose.theta_rad - origin.theta_rad))


def compose(base: Pose2D, delta: Pose2D) -> Pose2D:
    """delta (in base's frame) applied to base."""
    c, s = math.cos(base.theta_rad), math.sin(base.theta_rad)
    return Pose2D(base.x_m + c * delta.x_m - s * delta.y_m, base.y_m + s * delta.x_m + c * delta.y_m,
                  wrap_angle(base.theta_rad + delta.theta_rad))
