"""Plane geometry shared by the simulator and the skills."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Pose2D:
    """A pose on the floor: position [m] and heading [rad], counter-clockwise from +x."""

    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = 0.0

    def distance_to(self, other: Pose2D) -> float:
        """Euclidean distance between the two positions [m]."""
        return math.hypot(other.x_m - self.x_m, other.y_m - self.y_m)


def wrap_angle(angle_rad: float) -> float:
    """The same angle in [-pi, pi)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def yaw_from_quaternion(quaternion: tuple[float, float, float, float]) -> float:
    """Heading [rad] of an (x, y, z, w) quaternion, as pybullet returns them."""
    x, y, z, w = quaternion
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
