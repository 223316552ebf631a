"""The detect-obstacle perceptive skill's data object: obstacles seen by the laser, and clearance ahead."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.skills.base import Outcome, SensorLayout, SkillController, TickInput, feedback_for
from skill_server.skills.schema import ParameterSchema, ParameterType, SkillDescription

DETECT_OBSTACLE = "detect_obstacle"
GRID_RESOLUTION_M = 0.05
GRID_HALF_EXTENT_M = 10.0  # covers any room the lab builds around the start
HITS_TO_OCCUPY = 2  # one stray echo does not make an obstacle


class ObstacleMap:
    """Hit counts of laser echoes in a world-frame grid, placed at the pose the robot believes."""

    def __init__(self, resolution_m: float = GRID_RESOLUTION_M, half_extent_m: float = GRID_HALF_EXTENT_M) -> None:
        self.resolution_m = resolution_m
        self.origin_m = -half_extent_m
        self.size = int(round(2 * half_extent_m / resolution_m))
        self.hits = np.zeros((self.size, self.size), dtype=np.int16)  # indexed [ix, iy]
        self.version = 0

    def cell_of(self, x_m: float, y_m: float) -> tuple[int, int]:
        """Grid indices of a world point (may fall outside the grid)."""
        return (int(math.floor((x_m - self.origin_m) / self.resolution_m)),
                int(math.floor((y_m - self.origin_m) / self.resolution_m)))

    def center_of(self, ix: int, iy: int) -> tuple[float, float]:
        """World point at a cell's centre."""
        return (self.origin_m + (ix + 0.5) * self.resolution_m, self.origin_m + (iy + 0.5) * self.resolution_m)

    def add_scan(self, tick: TickInput) -> None:
        """Counts the laser's echoes at the believed pose."""
        ranges_m = np.asarray(tick.laser_ranges_m)
        angles_rad = tick.sensors.laser_angles_rad
        echoed = ranges_m < tick.sensors.laser.max_range_m - 1e-6
        if not echoed.any():
            return
        pose = tick.pose
        world_rad = pose.theta_rad + angles_rad[echoed]
        xs = pose.x_m + ranges_m[echoed] * np.cos(world_rad)
        ys = pose.y_m + ranges_m[echoed] * np.sin(world_rad)
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(int)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(int)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        np.add.at(self.hits, (ix[inside], iy[inside]), 1)
        np.minimum(self.hits, 1000, out=self.hits)
        self.version += 1

    def occupied(self) -> np.ndarray:
        """Boolean grid of cells seen as obstacles."""
        return self.hits >= HITS_TO_OCCUPY

    def occupied_window(self, x0: int, x1: int, y0: int, y1: int) -> np.ndarray:
        """The occupied cells of [x0:x1, y0:y1] only (cheaper than the whole grid)."""
        return self.hits[x0:x1, y0:y1] >= HITS_TO_OCCUPY


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

