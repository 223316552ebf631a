"""The wall_following skill: keep a distance to a contour on one side using the sonar ring."""

from __future__ import annotations

import math

import numpy as np

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, aborted, feedback_for
from skill_server.skills.obstacles import clearance

WALL_FOLLOWING = "wall_following"
CONE_EDGE_RAD = math.radians(12.5)
LOST_MARGIN_M = 0.8  # the wall counts as lost when the side reads this much beyond the set distance
GAP_BRIDGE_M = 0.45  # after losing the wall, drive straight this far before turning round its end
_ALPHAS = np.linspace(-0.55, 0.55, 111)  # candidate angles between heading and wall [rad]


def wall_following_description(spec: RobotSpec) -> SkillDescription:
    """The schema of wall_following."""
    return SkillDescription(
        name=WALL_FOLLOWING,
        title="Wall following",
        help=(
            "Follow a wall or any contour on one side using the sonars, keeping a set distance between the "
            "robot's rim and the contour; turns at inner corners, goes round outer corners and bridges short gaps."
        ),
        parameters=(
            ParameterSchema("distance_m", ParameterType.DOUBLE, "m", 0.15, 1.5, 0.4,
                            "Distance to keep between the robot's rim and the contour."),
            ParameterSchema("side", ParameterType.ENUM, "", 0.0, 0.0, 0.0,
                            "Which side the contour is on.", choices=("left", "right")),
            ParameterSchema("speed_mps", ParameterType.DOUBLE, "m/s", 0.05, spec.max_linear_mps, 0.3,
                            "Forward speed on straight runs."),
            ParameterSchema("duration_s", ParameterType.DOUBLE, "s", 0.0, 3600.0, 0.0,
                            "Stop and succeed after this long (0 = until cancelled)."),
        ),
    )


class WallFollowing(SkillController):
    """Estimates distance and angle to the wall from three side sonars; steers with a PD-like law."""

    skill_class = "sensorimotor"  # chooses its wheel commands from what the sensors report

    def __init__(self, distance_m: float, side: str, speed_mps: float, duration_s: float) -> None:
        super().__init__()
        self._target_m = distance_m
        self._sign = 1.0 if side == "left" else -1.0  # mirrors the right side onto the left
        self._speed_mps = speed_mps
        self._duration_s = duration_s
        self._started_s: float | None = None
        self._lost_at: tuple[float, float] | None = None  # odometry position where the wall was lost
        self._had_wall = False
        self._distance_m = distance_m
        self._alpha_rad = 0.0
        self._state = "searching"

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """One step of following."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        ranges = self._side_ranges(tick)
        radius_m = tick.sensors.sonar_mount_radius_m
        if tick.new_scan:
            self._estimate_wall(ranges, radius_m)
        front_m = min(ranges[0], ranges[22.5] + 0.05, clearance(tick).ahead_m)
        side_m = min(ranges[90.0], ranges[67.5], ranges[112.5])
        speed = self._speed_mps
        if front_m < self._target_m + 0.15 + speed * 0.6:
            # Inner corner: turn away from the wall on the spot until the way ahead is free.
            self._state, linear, angular = "corner", 0.02, -1.0
        elif side_m > self._target_m + LOST_MARGIN_M:
            linear, angular = self._round_the_end(tick, speed)
        else:
            if self._lost_at is not None:
                self.announce(EventKind.STEP_STARTED, "wall found again")
            self._lost_at, self._had_wall, self._state = None, True, "following"
            error_m = self._distance_m - self._target_m  # > 0: too far, steer toward the wall
            wanted_alpha = max(-0.35, min(0.35, 2.0 * error_m))
            angular = 3.0 * (wanted_alpha - self._alpha_rad)
            linear = speed * max(0.3, math.cos(self._alpha_rad) - 2.0 * abs(error_m))
        angular = max(-1.5, min(1.5, angular))
        # A timed run has a measurable progress (time followed); an open-ended one has none, so it stays 0.
        elapsed_s = tick.sim_time_s - self._started_s
        progress = elapsed_s / self._duration_s if self._duration_s > 0 else 0.0
        feedback = feedback_for(tick, self._state, progress, self._distance_m - self._target_m, self._alpha_rad,
                                wall_distance_m=self._distance_m, front_m=min(front_m, 9.0))
        outcome = None
        if self._duration_s > 0 and elapsed_s >= self._duration_s:
            outcome = Outcome(GoalStatus.SUCCEEDED, "", f"followed the contour for {self._duration_s:g} s")
        elif not self._had_wall and tick.sim_time_s - self._started_s > 30.0:
            outcome = aborted("NO_WALL", "no contour within reach on that side after 30 s")
        return linear, self._sign * angular, outcome, feedback

    def _side_ranges(self, tick: TickInput) -> dict[float, float]:
        # Readings by mount angle [deg] on the followed side (the right side mirrored onto the left).
        by_angle: dict[float, float] = {}
        for mount_rad, range_m in zip(tick.sensors.sonar_mount_rad, tick.sonar_ranges_m, strict=True):
            angle = round(math.degrees(mount_rad * self._sign), 1)
            by_angle[angle] = range_m
        return by_angle

    def _estimate_wall(self, ranges: dict[float, float], radius_m: float) -> None:
        # Sonars at 45 and 135 deg see a flat wall nearest at their cone edge closest to the perpendicular;
        # the angle that makes both agree on the wall's distance is the heading relative to the wall.
        r45, r135, r90 = ranges[45.0], ranges[135.0], ranges[90.0]
        if max(r45, r135) > self._target_m + LOST_MARGIN_M + 0.6:
            self._distance_m = r90
            return
        edge = math.pi / 2 - (math.radians(45.0) + CONE_EDGE_RAD)
        front = r45 * np.cos(edge - _ALPHAS) + radius_m * np.sin(math.radians(45.0) + _ALPHAS)
        rear = r135 * np.cos(edge + _ALPHAS) + radius_m * np.sin(math.radians(135.0) + _ALPHAS)
        best = int(np.argmin(np.abs(front - rear)))
        self._alpha_rad = float(_ALPHAS[best])
        centre_m = 0.5 * (front[best] + rear[best])
        if abs(self._alpha_rad) < CONE_EDGE_RAD:
            centre_m = min(centre_m, r90 + radius_m)  # the side sonar sees the perpendicular itself
        self._distance_m = centre_m - radius_m

    def _round_the_end(self, tick: TickInput, speed: float) -> tuple[float, float]:
        position = (tick.odometry.pose.x_m, tick.odometry.pose.y_m)
        if self._lost_at is None:
            self._lost_at = position
            if self._had_wall:
                self.announce(EventKind.WALL_LOST, "contour ends; going round it")
        if not self._had_wall:
            self._state = "searching"
            return speed, 0.0
        if math.dist(position, self._lost_at) < GAP_BRIDGE_M:
            self._state = "bridging"
            return speed, 0.0
        self._state = "rounding"
        turn_radius_m = self._target_m + tick.spec.body_radius_m + 0.1
        return 0.6 * speed, 0.6 * speed / turn_radius_m
