"""A ring of sonars, each a cone modelled by a fan of rays that reports its nearest echo."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D


@dataclass(frozen=True)
class SonarGeometry:
    """One sonar: where it points on the rim and what it can measure."""

    mount_angle_rad: float  # in the robot frame, 0 = ahead, counter-clockwise positive
    cone_half_angle_rad: float
    min_range_m: float
    max_range_m: float


@dataclass(frozen=True)
class SonarRingSpec:
    """The ring's layout: evenly spaced sonars on the body's rim, at one height."""

    count: int = 16
    cone_half_angle_rad: float = math.radians(12.5)
    rays_per_cone: int = 7
    min_range_m: float = 0.05
    max_range_m: float = 5.0
    mount_radius_m: float = 0.20  # [m] the body's radius: ranges are measured from the rim
    height_m: float = 0.15
    noise_std_m: float = 0.005

    def geometries(self) -> tuple[SonarGeometry, ...]:
        """Each sonar's geometry, sonar 0 straight ahead, then counter-clockwise."""
        return tuple(
            SonarGeometry(
                wrapped_mount_angle(2.0 * math.pi * i / self.count),
                self.cone_half_angle_rad,
                self.min_range_m,
                self.max_range_m,
            )
            for i in range(self.count)
        )


def wrapped_mount_angle(angle_rad: float) -> float:
    """A mount angle in (-pi, pi], so the sonar behind reads +pi."""
    wrapped = math.remainder(angle_rad, 2.0 * math.pi)
    return math.pi if math.isclose(wrapped, -math.pi) else wrapped


class SonarRing:
    """Turns the robot's pose into rays, and the rays' hits into one range per sonar."""

    def __init__(self, spec: SonarRingSpec) -> None:
        self.spec = spec
        mounts = np.array([g.mount_angle_rad for g in spec.geometries()])
        offsets = np.linspace(-spec.cone_half_angle_rad, spec.cone_half_angle_rad, spec.rays_per_cone)
        self._mount_rad = mounts  # [rad] robot frame, one per sonar
        self._ray_rad = (mounts[:, None] + offsets[None, :]).reshape(-1)  # [rad] robot frame, one per ray

    @property
    def ray_count(self) -> int:
        """How many rays one reading casts."""
        return int(self._ray_rad.size)

    def rays(self, pose: Pose2D, single_ray: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Start and end points (N x 3, world frame) of every ray; single_ray keeps only each axis."""
        spec = self.spec
        sensor_rad = pose.theta_rad + self._mount_rad
        starts = np.stack(
            [
                pose.x_m + spec.mount_radius_m * np.cos(sensor_rad),
                pose.y_m + spec.mount_radius_m * np.sin(sensor_rad),
                np.full(sensor_rad.shape, spec.height_m),
            ],
            axis=1,
        )
        if single_ray:
            directions = sensor_rad
        else:
            starts = np.repeat(starts, spec.rays_per_cone, axis=0)
            directions = pose.theta_rad + self._ray_rad
        ends = starts + spec.max_range_m * np.stack(
            [np.cos(directions), np.sin(directions), np.zeros(directions.shape)], axis=1
        )
        return starts, ends

    def ranges(
        self, hit_fractions: np.ndarray, rng: np.random.Generator | None, single_ray: bool = False
    ) -> np.ndarray:
        """One range per sonar [m]: the nearest echo in its cone, max range when nothing echoes."""
        spec = self.spec
        per_sonar = hit_fractions.reshape(spec.count, 1 if single_ray else spec.rays_per_cone).min(axis=1)
        ranges_m = per_sonar * spec.max_range_m
        echoed = per_sonar < 1.0
        if rng is not None:
            ranges_m = ranges_m + echoed * rng.normal(0.0, spec.noise_std_m, spec.count)
        return np.where(echoed, np.clip(ranges_m, spec.min_range_m, spec.max_range_m), spec.max_range_m)
