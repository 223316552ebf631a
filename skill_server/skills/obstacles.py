"""The detect-obstacle perceptive skill's data object: obstacles seen by the laser, and clearance ahead."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.skills.base import Outcome, SensorLayout, SkillController, TickInput, feedback_for

DETECT_OBSTACLE = "detect_obstacle"
GRID_RESOLUTION_M = 0.05
GRID_HALF_EXTENT_M = 10.0  # covers any room the lab builds around the start
HITS_TO_OCCUPY = 2  # one stray echo does not make an obstacle
HITS_CAP = 8  # evidence saturates, so a few looks through a cell clear an echo placed by a pose that has drifted
CLEAR_RANGE_M = 3.5  # a laser ray is evidence of free space up to this far (the planner looks 2.5 m around)
CLEAR_STEP_M = 0.05  # spacing of the points sampled along a ray
VISITED_RADIUS_M = 0.08  # cells this close to where the robot's centre was count as places it has stood
BODY_CLEAR_MARGIN_M = 0.03  # the body's disk less this is cleared at every scan: nothing can stand inside the robot


def disk_offsets(radius_cells: float) -> tuple[np.ndarray, np.ndarray]:
    """Cell offsets (dx, dy) whose centres lie within radius_cells of the centre cell's."""
    reach = int(math.floor(radius_cells))
    dx, dy = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    inside = dx * dx + dy * dy <= radius_cells * radius_cells
    return dx[inside], dy[inside]


class ObstacleMap:
    """Laser evidence in a world-frame grid, placed at the pose the robot believes, with evidence both ways.

    Echoes add to a cell's count (saturating at HITS_CAP); a ray that passes through a cell takes one away, and
    the robot's own disk is cleared, so echoes placed at a pose that has since drifted, or left by an obstacle seen
    from afar, fade when the robot looks again. Cells the robot's centre has passed over are remembered as visited.
    """

    def __init__(self, resolution_m: float = GRID_RESOLUTION_M, half_extent_m: float = GRID_HALF_EXTENT_M) -> None:
        self.resolution_m = resolution_m
        self.origin_m = -half_extent_m
        self.size = int(round(2 * half_extent_m / resolution_m))
        # One spare element past the grid takes the writes of ray points that are not free (so no masking is needed).
        self._spare = self.size * self.size
        self._hits_flat = np.zeros(self._spare + 1, dtype=np.int16)
        self._seen_free_flat = np.zeros(self._spare + 1, dtype=bool)
        self.hits = self._hits_flat[:self._spare].reshape(self.size, self.size)  # indexed [ix, iy]
        self.seen_free = self._seen_free_flat[:self._spare].reshape(self.size, self.size)  # a ray passed through
        self.visited = np.zeros((self.size, self.size), dtype=bool)
        self.version = 0
        self._ray_steps_m = np.arange(CLEAR_STEP_M, CLEAR_RANGE_M, CLEAR_STEP_M)
        self._disks: dict[float, tuple[np.ndarray, np.ndarray]] = {}  # offsets by radius [m]

    def forget(self) -> None:
        """Drops every echo, free pass and visit, in place (holders keep the same grid; the version goes on)."""
        self._hits_flat[:] = 0
        self._seen_free_flat[:] = False
        self.visited[:] = False
        self.version += 1

    def cell_of(self, x_m: float, y_m: float) -> tuple[int, int]:
        """Grid indices of a world point (may fall outside the grid)."""
        return (int(math.floor((x_m - self.origin_m) / self.resolution_m)),
                int(math.floor((y_m - self.origin_m) / self.resolution_m)))

    def center_of(self, ix: int, iy: int) -> tuple[float, float]:
        """World point at a cell's centre."""
        return (self.origin_m + (ix + 0.5) * self.resolution_m, self.origin_m + (iy + 0.5) * self.resolution_m)

    def add_scan(self, tick: TickInput) -> None:
        """Clears the cells the laser sees through and the robot's own disk, then counts the echoes."""
        ranges_m = np.asarray(tick.laser_ranges_m)
        pose = tick.pose
        world_rad = pose.theta_rad + tick.sensors.laser_angles_rad
        cos, sin = np.cos(world_rad), np.sin(world_rad)
        echoed = ranges_m < tick.sensors.laser.max_range_m - 1e-6
        hit_ix, hit_iy = self._cells(pose.x_m + ranges_m[echoed] * cos[echoed],
                                     pose.y_m + ranges_m[echoed] * sin[echoed])
        hit_flat = hit_ix * self.size + hit_iy
        # Free evidence stops a cell short of each echo; a cell with an echo in this scan is not cleared by it.
        free_m = np.where(echoed, ranges_m - self.resolution_m, CLEAR_RANGE_M)
        scale = 1.0 / self.resolution_m
        ix = ((pose.x_m - self.origin_m) * scale + np.outer(cos, self._ray_steps_m * scale)).astype(np.int64)
        iy = ((pose.y_m - self.origin_m) * scale + np.outer(sin, self._ray_steps_m * scale)).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        free = (self._ray_steps_m[None, :] < free_m[:, None]) & inside
        free_flat = np.where(free, ix * self.size + iy, self._spare).reshape(-1)
        kept = self._hits_flat[hit_flat]
        self._hits_flat[free_flat] = np.maximum(self._hits_flat[free_flat] - 1, 0)
        self._hits_flat[hit_flat] = kept
        self._seen_free_flat[free_flat] = True
        body_ix, body_iy = self._disk_cells(pose.x_m, pose.y_m, tick.spec.body_radius_m - BODY_CLEAR_MARGIN_M)
        self.hits[body_ix, body_iy] = 0
        visited_ix, visited_iy = self._disk_cells(pose.x_m, pose.y_m, VISITED_RADIUS_M)
        self.visited[visited_ix, visited_iy] = True
        np.add.at(self._hits_flat, hit_flat, 1)
        self._hits_flat[hit_flat] = np.minimum(self._hits_flat[hit_flat], HITS_CAP)
        self.version += 1

    def _cells(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Grid indices of world points, those outside the grid left out."""
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        return ix[inside], iy[inside]

    def _disk_cells(self, x_m: float, y_m: float, radius_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Cells whose centres lie within radius_m of the cell holding (x_m, y_m), inside the grid."""
        offsets = self._disks.get(radius_m)
        if offsets is None:
            offsets = self._disks[radius_m] = disk_offsets(radius_m / self.resolution_m)
        cx, cy = self.cell_of(x_m, y_m)
        ix, iy = offsets[0] + cx, offsets[1] + cy
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        return ix[inside], iy[inside]

    def occupied(self) -> np.ndarray:
        """Boolean grid of cells seen as obstacles."""
        return self.hits >= HITS_TO_OCCUPY

    def occupied_window(self, x0: int, x1: int, y0: int, y1: int) -> np.ndarray:
        """The occupied cells of [x0:x1, y0:y1] only (cheaper than the whole grid)."""
        return self.hits[x0:x1, y0:y1] >= HITS_TO_OCCUPY

    def was_visited(self, x_m: float, y_m: float) -> bool:
        """Whether the robot's centre has stood within about VISITED_RADIUS_M of this point."""
        ix, iy = self.cell_of(x_m, y_m)
        return 0 <= ix < self.size and 0 <= iy < self.size and bool(self.visited[ix, iy])


@dataclass(frozen=True)
class Clearance:
    """Free distance from the robot's rim along its heading, forward and backward [m]."""

    ahead_m: float
    behind_m: float
    nearest_m: float  # nearest echo in any direction, from the rim


_last_clearance: list[tuple[object, object, float, float, Clearance]] = []  # one entry: readings change at 20 Hz


def clearance(tick: TickInput, corridor_margin_m: float = 0.04) -> Clearance:
    """How far the robot can drive straight before touching what the laser and sonars see."""
    # Readings are immutable tuples replaced on every scan, so the same objects mean the same answer.
    if _last_clearance:
        laser, sonar, margin_m, radius_m, cached = _last_clearance[0]
        if (laser is tick.laser_ranges_m and sonar is tick.sonar_ranges_m and margin_m == corridor_margin_m
                and radius_m == tick.spec.body_radius_m):
            return cached
    result = _clearance(tick, corridor_margin_m)
    _last_clearance[:] = [(tick.laser_ranges_m, tick.sonar_ranges_m, corridor_margin_m, tick.spec.body_radius_m,
                           result)]
    return result


def _clearance(tick: TickInput, corridor_margin_m: float) -> Clearance:
    sensors: SensorLayout = tick.sensors
    radius_m = tick.spec.body_radius_m
    half_width_m = radius_m + corridor_margin_m
    ahead_m = behind_m = math.inf
    ranges_m = np.asarray(tick.laser_ranges_m)
    angles_rad = sensors.laser_angles_rad
    xs, ys = ranges_m * np.cos(angles_rad), ranges_m * np.sin(angles_rad)
    in_corridor = (np.abs(ys) < half_width_m) & (xs > 0) & (ranges_m < sensors.laser.max_range_m - 1e-6)
    if in_corridor.any():
        # A box edge at lateral offset y is met by the round body before its centre reaches x.
        reach = np.sqrt(np.maximum(radius_m**2 - np.minimum(np.abs(ys[in_corridor]), radius_m) ** 2, 0.0))
        ahead_m = float(np.min(xs[in_corridor] - reach))
    sonar_m = np.asarray(tick.sonar_ranges_m)
    mounts = np.asarray(sensors.sonar_mount_rad)
    nearest_m = float(sonar_m.min()) if sonar_m.size else math.inf
    front = np.abs(np.cos(mounts)) > math.cos(math.radians(25.0))
    for sign in (1.0, -1.0):
        facing = front & (np.sign(np.cos(mounts)) == sign)
        if facing.any():
            closest = float(sonar_m[facing].min())
            if sign > 0:
                ahead_m = min(ahead_m, closest)
            else:
                behind_m = min(behind_m, closest)
    return Clearance(ahead_m, behind_m, nearest_m)


def detect_obstacle_description() -> SkillDescription:
    """The schema of detect_obstacle."""
    return SkillDescription(
        name=DETECT_OBSTACLE,
        title="Detect obstacle",
        help=(
            "Perceptive skill: watches the laser and sonars and announces an obstacle whenever something comes "
            "closer to the robot's rim than the warning distance. Runs beside any motor skill; go-to-goal uses "
            "the same obstacle data to plan around what it sees."
        ),
        parameters=(
            ParameterSchema("warning_distance_m", ParameterType.DOUBLE, "m", 0.05, 3.0, 0.4,
                            "Announce an obstacle closer than this to the robot's rim."),
            ParameterSchema("duration_s", ParameterType.DOUBLE, "s", 0.0, 3600.0, 0.0,
                            "Stop watching after this much time (0 = until cancelled)."),
        ),
    )


class DetectObstacle(SkillController):
    """Announces OBSTACLE_DETECTED each time the nearest echo enters the warning distance."""

    motor = False
    skill_class = "perceptive"

    def __init__(self, warning_distance_m: float, duration_s: float) -> None:
        super().__init__()
        self._warning_m = warning_distance_m
        self._duration_s = duration_s
        self._started_s: float | None = None
        self._inside = False
        self._detections = 0

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Watches the nearest echo; ends by itself only when a duration was given."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        free = clearance(tick)
        nearest_m = min(free.nearest_m, free.ahead_m)
        inside = nearest_m < self._warning_m
        if inside and not self._inside:
            self._detections += 1
            self.announce(EventKind.OBSTACLE_DETECTED, f"obstacle {nearest_m:.2f} m from the rim")
        self._inside = inside
        feedback = feedback_for(
            tick, "obstacle" if inside else "clear", 0.0, nearest_m, 0.0,
            nearest_m=nearest_m, ahead_m=min(free.ahead_m, 99.0), detections=float(self._detections),
        )
        outcome = None
        if self._duration_s > 0 and tick.sim_time_s - self._started_s >= self._duration_s:
            outcome = Outcome(status=GoalStatus.SUCCEEDED, message=f"watched for {self._duration_s:g} s, "
                              f"{self._detections} detections")
        return 0.0, 0.0, outcome, feedback

