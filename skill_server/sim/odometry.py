"""Wheel odometry integrated from the wheel angles, with seeded noise so it drifts like a real one."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D, wrap_angle
from skill_server.sim.robot_model import RobotSpec


@dataclass(frozen=True)
class OdometryNoise:
    """How wrong the wheel encoders are."""

    scale_error_std: float = 0.004  # a fixed per-wheel calibration error, drawn once per seed
    increment_noise_std: float = 0.02  # multiplicative noise on a wheel-angle increment of reference_dt_s
    # The drift a distance gathers must not depend on how often the loop reads the wheels: a longer increment gets
    # proportionally less relative noise (independent noise sums: the std scales with the root of the count).
    reference_dt_s: float = 1.0 / 60.0


@dataclass(frozen=True)
class OdometryReading:
    """The pose and velocities the robot believes it has."""

    pose: Pose2D
    linear_mps: float
    angular_radps: float


class WheelOdometry:
    """Dead reckoning from the two wheel angles; heading error grows with distance travelled."""

    def __init__(
        self, spec: RobotSpec, start: Pose2D, rng: np.random.Generator, noise: OdometryNoise = OdometryNoise()
    ) -> None:
        self._spec = spec
        self._rng = rng
        self._noise = noise
        self._scale_left = 1.0 + float(rng.normal(0.0, noise.scale_error_std))
        self._scale_right = 1.0 + float(rng.normal(0.0, noise.scale_error_std))
        self._last_angles_rad: tuple[float, float] | None = None
        self.reading = OdometryReading(start, 0.0, 0.0)

    def update(self, left_angle_rad: float, right_angle_rad: float, dt_s: float) -> OdometryReading:
        """Integrates the wheel angles read after a tick of dt_s seconds."""
        if self._last_angles_rad is None:
            self._last_angles_rad = (left_angle_rad, right_angle_rad)
            return self.reading
        last_left, last_right = self._last_angles_rad
        self._last_angles_rad = (left_angle_rad, right_angle_rad)
        jitter_std = self._noise.increment_noise_std * math.sqrt(self._noise.reference_dt_s / dt_s)
        jitter = self._rng.normal(0.0, jitter_std, 2).tolist()
        left_m = (left_angle_rad - last_left) * self._spec.wheel_radius_m * self._scale_left * (1.0 + jitter[0])
        right_m = (right_angle_rad - last_right) * self._spec.wheel_radius_m * self._scale_right * (1.0 + jitter[1])
        distance_m = (left_m + right_m) / 2.0
        turn_rad = (right_m - left_m) / self._spec.wheel_base_m
        pose = self.reading.pose
        mid_heading_rad = pose.theta_rad + turn_rad / 2.0
        new_pose = Pose2D(
            pose.x_m + distance_m * math.cos(mid_heading_rad),
            pose.y_m + distance_m * math.sin(mid_heading_rad),
            wrap_angle(pose.theta_rad + turn_rad),
        )
        self.reading = OdometryReading(new_pose, distance_m / dt_s, turn_rad / dt_s)
        return self.reading
