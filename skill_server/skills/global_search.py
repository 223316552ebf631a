"""Global localization: where on the map a panorama of laser scans fits, for a guess that is unknown or wrong.

One 180-degree scan fits several places of a rectangular lab almost equally (80-97 % of its echoes on a wall
at wrong poses), which is why a particle filter seeded everywhere claimed wrong poses. A panorama (the scans of
a turn or a drive, put together by odometry, which is good over a few metres and one turn) sees the furniture
on every side. The search scores every free position and heading of the map against the panorama (coarse,
then refined around the best few), and answers only when one place clearly fits best: the best must put most
points on the map's surfaces, and the best place at least DISTINCT away must be far less likely. Likelihood,
not the share of points on a surface, decides: from a corner of the lab the place turned by 180 degrees puts
91 % of the points on a wall against 100 % at the truth, and only the few points on furniture tell them apart.
Otherwise it says how many places fit, and the robot should turn or drive further.

A whole-map search of the lab is about 40 million point lookups: 0.35-0.7 s of CPU at once, several seconds on a
loaded host, during which the world's loop (which runs the skills) neither stepped nor published, and the gRPC
handlers waited for the interpreter. `SlicedSearch` does the same work in slices of at most STEP_LOOKUPS lookups,
one slice per filter update, so the loop keeps its rate and Drive its deadline whatever the search costs.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.skills.scan_matching import compose, relative

COARSE_STEP_M, COARSE_STEP_RAD = 0.15, math.radians(4.0)
FINE_STEP_M, FINE_STEP_RAD = 0.03, math.radians(1.0)
COARSE_SIGMA_M, FINE_SIGMA_M = 0.12, 0.05
MIN_CLEARANCE_M = 0.15  # the robot stands in free space
VOXEL_M = 0.12  # the panorama is thinned to one point per cell of this size
MAX_POINTS = 240
REFINED = 12  # coarse candidates refined
DISTINCT_M, DISTINCT_RAD = 0.5, math.radians(30.0)  # a second place this far from the best is another answer
MIN_INLIERS = 0.8  # of the panorama's points within 3 fine sigma of a surface at the answer
RANDOM_POINT_LIKELIHOOD = 0.05  # per point, for what the map lacks (as the filter's random-echo floor)
LIKELIHOOD_TEMPER = 3.0  # neighbouring points are not independent
MIN_LOG_RATIO = 4.0  # the best place must be e^4 (about 55) times as likely as any other place
PANORAMA_SWEEP_RAD = math.radians(300.0)  # heading swept (or PANORAMA_TRAVEL_M driven) before a search
PANORAMA_TRAVEL_M = 1.0
MAX_SCANS = 240
# Point lookups per slice of a sliced search (two headings of the lab's coarse search, about 10 ms of CPU): the
# lab's whole-map search then takes about 50 slices, 2.5 s of filter updates at 20 Hz.
STEP_LOOKUPS = 900_000
REFINED_PER_STEP = 4


@dataclass(frozen=True)
class Region:
    """Where a guess says the robot is: within radius_m of centre, heading within spread_rad of centre's."""

    centre: Pose2D
    radius_m: float
    spread_rad: float


@dataclass(frozen=True)
class SearchResult:
    """The answer of one search: the anchor's pose on the map if one place clearly fits, and how many fit."""

    anchor_pose: Pose2D | None  # the panorama's anchor (its first odometry pose) on the map; None if ambiguous
    inliers: float  # fraction of points near a surface at the best place
    places: int  # distinct places within MIN_LOG_RATIO of the best (1 when clear)


class Panorama:
    """The echoes of the scans since the search began, in the frame of the first scan's odometry pose."""

    def __init__(self) -> None:
        self.anchor: Pose2D | None = None
        self._last: Pose2D | None = None
        self._points: list[np.ndarray] = []
        self.swept_rad = 0.0
        self.travelled_m = 0.0

    @property
    def scans(self) -> int:
        return len(self._points)

    def add(self, odometry: Pose2D, ranges_m: np.ndarray, angles_rad: np.ndarray) -> None:
        """One scan's echoes (ranges already limited to real echoes) at an odometry pose."""
        if self.anchor is None:
            self.anchor = odometry
        if self._last is not None:
            step = relative(self._last, odometry)
            self.swept_rad += abs(step.theta_rad)
            self.travelled_m += math.hypot(step.x_m, step.y_m)
        self._last = odometry
        at = relative(self.anchor, odometry)
        world = at.theta_rad + angles_rad
        self._points.append(np.column_stack([at.x_m + ranges_m * np.cos(world), at.y_m + ranges_m * np.sin(world)]))
        if len(self._points) > MAX_SCANS:
            self._points = self._points[::2]  # keeps the whole sweep, thinner

    @property
    def ready(self) -> bool:
        """Whether the scans so far see enough of the lab to search with."""
        return self.swept_rad >= PANORAMA_SWEEP_RAD or self.travelled_m >= PANORAMA_TRAVEL_M

    def points(self) -> np.ndarray:
        """The panorama thinned to one point per VOXEL_M cell, at most MAX_POINTS."""
        if not self._points:
            return np.zeros((0, 2))
        points = np.concatenate(self._points)
        _, first = np.unique(np.floor(points / VOXEL_M).astype(np.int64), axis=0, return_index=True)
        thinned = points[np.sort(first)]
        return thinned[:: max(1, math.ceil(len(thinned) / MAX_POINTS))]

    def pose_now(self, anchor_on_map: Pose2D, odometry: Pose2D) -> Pose2D:
        """Where the robot is on the map now, given where the anchor is."""
        assert self.anchor is not None
        return compose(anchor_on_map, relative(self.anchor, odometry))


class FieldLookup:
    """Distance [m] to the nearest surface of a map, by nearest cell (fast enough for a whole-map search)."""

    def __init__(self, field: np.ndarray, origin_m: float, resolution_m: float) -> None:
        self.field, self.origin_m, self.resolution_m = field, origin_m, resolution_m
        self.size = field.shape[0]

    def at(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        ix = np.clip(((xs - self.origin_m) / self.resolution_m).astype(np.int64), 0, self.size - 1)
        iy = np.clip(((ys - self.origin_m) / self.resolution_m).astype(np.int64), 0, self.size - 1)
        return self.field[ix, iy]

    def free_positions(self, known_free: np.ndarray, step_m: float) -> np.ndarray:
        """Cell centres every step_m that are known free with MIN_CLEARANCE_M to the nearest surface."""
        stride = max(1, round(step_m / self.resolution_m))
        ix, iy = np.nonzero(known_free[::stride, ::stride] & (self.field[::stride, ::stride] >= MIN_CLEARANCE_M))
        centres = self.origin_m + (np.column_stack([ix, iy]) * stride + 0.5) * self.resolution_m
        return centres.astype(float)


class CoarseScores:
    """_scores at COARSE_SIGMA_M for positions on cell centres, equal to it and 3-4 times cheaper: the Gaussian of
    each cell's distance is taken once (not once per lookup), and the map is padded with its edge cells by the
    panorama's reach, so a lookup is one integer addition (cell of the position + cell offset of the point) with no
    clipping. (x - origin) / resolution is the cell index plus a half at a centre, hence the offsets' extra half."""

    def __init__(self, lookup: FieldLookup, points: np.ndarray, positions: np.ndarray) -> None:
        resolution = lookup.resolution_m
        reach = int(math.ceil(float(np.max(np.hypot(points[:, 0], points[:, 1]), initial=0.0)) / resolution)) + 2
        likelihood = np.exp(-0.5 * (lookup.field / COARSE_SIGMA_M) ** 2)
        padded = np.pad(likelihood, reach, mode="edge")
        self._row = padded.shape[1]
        self._likelihood = padded.ravel()
        cells = np.floor((positions - lookup.origin_m) / resolution).astype(np.int64) + reach
        self._base = cells[:, 0] * self._row + cells[:, 1]
        self._points_cells = points / resolution

    def at(self, theta: float) -> np.ndarray:
        """The mean likelihood of the points turned by theta, at every position."""
        c, s = math.cos(theta), math.sin(theta)
        px, py = self._points_cells[:, 0], self._points_cells[:, 1]
        off_x = np.floor(0.5 + c * px - s * py).astype(np.int64)
        off_y = np.floor(0.5 + s * px + c * py).astype(np.int64)
        return self._likelihood[self._base[:, None] + (off_x * self._row + off_y)[None, :]].mean(axis=1)


def _scores(lookup: FieldLookup, points: np.ndarray, positions: np.ndarray, theta: float, sigma_m: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    rx, ry = c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1]
    d = lookup.at(positions[:, 0:1] + rx[None, :], positions[:, 1:2] + ry[None, :])
    return np.mean(np.exp(-0.5 * (d / sigma_m) ** 2), axis=1)


def _refine(lookup: FieldLookup, points: np.ndarray, pose: Pose2D) -> tuple[Pose2D, float]:
    """The best pose near pose, and its tempered log-likelihood."""
    offsets = np.arange(-2, 3) * FINE_STEP_M
    grid = np.array([(pose.x_m + dx, pose.y_m + dy) for dx in offsets for dy in offsets])
    best, best_score = pose, -1.0
    for k in range(-4, 5):
        theta = pose.theta_rad + k * FINE_STEP_RAD
        scores = _scores(lookup, points, grid, theta, FINE_SIGMA_M)
        i = int(np.argmax(scores))
        if scores[i] > best_score:
            best, best_score = Pose2D(float(grid[i, 0]), float(grid[i, 1]), theta), float(scores[i])
    gaps = _gaps(lookup, points, best)
    likelihood = np.exp(-0.5 * (gaps / FINE_SIGMA_M) ** 2) + RANDOM_POINT_LIKELIHOOD
    return best, float(np.sum(np.log(likelihood)) / LIKELIHOOD_TEMPER)


def _distinct(a: Pose2D, b: Pose2D) -> bool:
    turn = abs(math.remainder(a.theta_rad - b.theta_rad, 2 * math.pi))
    return math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) > DISTINCT_M or turn > DISTINCT_RAD


def search(lookup: FieldLookup, known_free: np.ndarray, points: np.ndarray,
           region: Region | None = None) -> SearchResult:
    """Where the panorama's anchor is on the map (within region, if given), if one place clearly fits best."""
    for result in _search_steps(lookup, known_free, points, region, step_lookups=None):
        if result is not None:
            return result
    raise AssertionError("a search always ends with a result")


class SlicedSearch:
    """search() spread over calls of step(), each doing at most about STEP_LOOKUPS point lookups (at least one
    heading of the coarse search, or REFINED_PER_STEP refinements), for a caller in the world's loop."""

    def __init__(self, lookup: FieldLookup, known_free: np.ndarray, points: np.ndarray,
                 region: Region | None = None, step_lookups: int = STEP_LOOKUPS) -> None:
        self._steps = _search_steps(lookup, known_free, points, region, step_lookups)
        self.steps_taken = 0

    def step(self) -> SearchResult | None:
        """One more slice: the result once the search is over, None until then."""
        self.steps_taken += 1
        return next(self._steps)


def _search_steps(lookup: FieldLookup, known_free: np.ndarray, points: np.ndarray, region: Region | None,
                  step_lookups: int | None) -> Iterator[SearchResult | None]:
    """The search, yielding None after each slice of about step_lookups lookups (None: no slicing), then the
    result."""
    positions = lookup.free_positions(known_free, COARSE_STEP_M)
    headings = np.arange(-math.pi, math.pi, COARSE_STEP_RAD)
    if region is not None:
        centre = region.centre
        positions = positions[np.hypot(positions[:, 0] - centre.x_m, positions[:, 1] - centre.y_m) <= region.radius_m]
        turns = np.abs(np.remainder(headings - centre.theta_rad + math.pi, 2 * math.pi) - math.pi)
        headings = headings[turns <= region.spread_rad]
    if len(points) < 20 or len(positions) == 0 or len(headings) == 0:
        yield SearchResult(None, 0.0, 0)
        return
    per_heading = len(positions) * len(points)
    headings_per_step = len(headings) if step_lookups is None else max(1, step_lookups // per_heading)
    coarse = CoarseScores(lookup, points, positions)
    candidates: list[tuple[float, Pose2D]] = []
    for k, theta in enumerate(headings):
        if k and k % headings_per_step == 0:
            yield None
        scores = coarse.at(float(theta))
        for i in np.argsort(scores)[-3:]:
            candidates.append((float(scores[i]), Pose2D(float(positions[i, 0]), float(positions[i, 1]), float(theta))))
    candidates.sort(key=lambda c: -c[0])
    kept: list[Pose2D] = []
    for _, pose in candidates:  # the best few distinct places, not the same place at neighbouring headings
        if all(_distinct(pose, other) for other in kept):
            kept.append(pose)
        if len(kept) == REFINED:
            break
    refined: list[tuple[Pose2D, float]] = []
    for k, pose in enumerate(kept):
        if step_lookups is not None and k % REFINED_PER_STEP == 0:
            yield None
        refined.append(_refine(lookup, points, pose))
    refined.sort(key=lambda r: -r[1])
    best, best_score = refined[0]
    rivals = [score for pose, score in refined[1:] if _distinct(pose, best)]
    runner_up = max(rivals, default=-math.inf)
    gaps = np.abs(_gaps(lookup, points, best))
    inliers = float(np.mean(gaps < 3.0 * FINE_SIGMA_M))
    places = 1 + sum(score > best_score - MIN_LOG_RATIO for score in rivals)
    clear = inliers >= MIN_INLIERS and runner_up <= best_score - MIN_LOG_RATIO
    yield SearchResult(best if clear else None, inliers, places)


def _gaps(lookup: FieldLookup, points: np.ndarray, pose: Pose2D) -> np.ndarray:
    c, s = math.cos(pose.theta_rad), math.sin(pose.theta_rad)
    return lookup.at(pose.x_m + c * points[:, 0] - s * points[:, 1], pose.y_m + s * points[:, 0] + c * points[:, 1])
