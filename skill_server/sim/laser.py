"""A planar laser scanner sweeping the half-plane in front of the robot."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.sim.geometry import Pose2D


@dataclass(frozen=True)
class LaserSpec:
    """The scanner's sweep; it sits on the robot's centre, so ranges are measured from the centre."""

    angle_min_rad: float = -math.pi / 2.0
    angle_max_rad: float = math.pi / 2.0
    beam_count: int = 181
    min_range_m: float = 0.05
    max_range_m: float = 8.0
    height_m: float = 0.20  # [m] above the body's top, below the camera
    noise_std_m: float = 0.003

    @property
    def angle_increment_rad(self) -> float:
        """Angle between neighbouring beams."""
        return (self.angle_max_rad - self.angle_min_rad) / (self.beam_count - 1)


class Laser:
    """Turns the robot's pose into beams, and the beams' hits into ranges."""

    def __init__(self, spec: LaserSpec) -> None:
        self.spec = spec
        self._beam_rad = np.linspace(spec.angle_min_rad, spec.angle_max_rad, spec.beam_count)

    @property
    def ray_count(self) -> int:
        """How many rays one scan casts."""
        return self.spec.beam_count

    def rays(self, pose: Pose2D) -> tuple[np.ndarray, np.ndarray]:
        """Start and end points (N x 3, world frame) of every beam."""
        spec = self.spec
        directions = pose.theta_rad + self._beam_rad
        starts = np.tile([pose.x_m, pose.y_m, spec.height_m], (spec.beam_count, 1))
        ends = starts + spec.max_range_m * np.stack(
            [np.cos(directions), np.sin(directions), np.zeros(directions.shape)], axis=1
        )
        return starts, ends

    def ranges(self, hit_fractions: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
        """One range per beam [m], max range when nothing is hit."""
        spec = self.spec
        ranges_m = hit_fractions * spec.max_range_m
        hit = hit_fractions < 1.0
        if rng is not None:
            ranges_m = ranges_m + hit * rng.normal(0.0, spec.noise_std_m, spec.beam_count)
        return np.where(hit, np.clip(ranges_m, spec.min_range_m, spec.max_range_m), spec.max_range_m)
