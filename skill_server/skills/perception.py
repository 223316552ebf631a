"""The data objects perceptive skills share with the others (the paper's data objects), and what they publish."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import SceneSpec
from skill_server.skills.environment_model import EnvironmentModel, PublishedGrid
from skill_server.skills.obstacles import ObstacleMap
from skill_server.skills.scan_matching import compose, relative


@dataclass(frozen=True)
class LocalizationEstimate:
    """What the filter believes, published for streams (immutable)."""

    pose: Pose2D
    std_x_m: float
    std_y_m: float
    std_theta_rad: float
    converged: bool
    update_duration_ms: float
    particles: tuple[tuple[float, float, float, float], ...]
    odometry: Pose2D | None = None  # the odometry reading pose was moved on to (readers extrapolate from it)
    residual_rms_m: float = 0.0  # RMS distance of the scan's echoes to the map at the estimate
    particle_std_m: float = 0.0  # the cloud's own spread, hypot(x, y), before the map-mismatch term

    def pose_at(self, odometry: Pose2D) -> Pose2D:
        """The estimate moved on to a later odometry reading: the filter publishes during a tick from the previous
        tick's readings, so a reader beside a newer snapshot (its truth, its odometry) compares at the same instant.
        """
        if self.odometry is None:
            return self.pose
        return compose(self.pose, relative(self.odometry, odometry))


@dataclass(frozen=True)
class NavigationPose:
    """The pose the skills steer by at the last tick and where it came from ("localization", "map tracking",
    "odometry"), published for streams (immutable)."""

    pose: Pose2D
    source: str


class PoseEstimator(Protocol):
    """A running skill that estimates the robot's pose (localization)."""

    def believed_pose(self, odometry: Pose2D) -> Pose2D | None:
        """The estimate moved on to the given odometry reading; None until it is trusted."""
        ...


class Perception:
    """What the sequencer hands every skill it builds; written and read in the world's loop only."""

    def __init__(self) -> None:
        self.obstacles = ObstacleMap()
        self.environment: EnvironmentModel | None = None  # the occupancy grid, kept after mapping ends
        self.localizer: PoseEstimator | None = None  # the running pose estimator, if any
        self.published_map: PublishedGrid | None = None  # the latest immutable grid, for GetMap
        self.published_estimate: LocalizationEstimate | None = None  # the latest immutable estimate, for streams
        self.navigation: NavigationPose | None = None  # the pose the skills steer by, for streams
        self.floor_plan: SceneSpec | None = None  # the lab as built, which mapping may start from
