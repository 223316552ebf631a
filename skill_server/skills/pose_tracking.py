"""The navigation stack's own pose tracking: localization kept running against the lab's floor plan.

A real navigation stack keeps localization running against the map of the building it drives in (AMCL beside
the planner), so a goal it reports reached is reached. Wheel odometry alone drifts: in the benchmark's go-to-goal
to 60 free points one after another, 5 % were reached by the true pose and 41 were reported reached while the
robot stood up to 3.6 m away. The tracker starts at a known pose (the dock at start-up, wherever the robot is
placed after a reset or a return to the dock) and follows it with the same particle filter as the localization
skill; the skill, when a person runs it, is the one that is shown and takes precedence.
"""

from __future__ import annotations

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import SceneSpec
from skill_server.skills.base import TickInput
from skill_server.skills.environment_model import EnvironmentModel
from skill_server.skills.localization import Localization
from skill_server.skills.perception import Perception

POSE_SOURCE = "map tracking"
TRACKER_PARTICLES = 200
START_SPREAD_M, START_SPREAD_RAD = 0.02, 0.02  # a placement is known to the centimetre


class PoseTracker:
    """Follows the robot's pose against the floor plan from a known start; None when it lost track.

    Built before the world's loop starts, with its map's field computed then (40 ms), so the loop's first ticks
    stay as quick as the others.
    """

    def __init__(self, floor_plan: SceneSpec, seed: int = 11) -> None:
        self._model = EnvironmentModel()
        self._model.add_floor_plan(floor_plan)
        self._seed = seed
        self._filter = self._filter_at(floor_plan.spawn, None)  # a world starts at its spawn, odometry exact
        self._field = self._filter.field  # computed now, and shared by the filters of later restarts
        self._restart_pending = False

    def restart(self) -> None:
        """Starts again at the next tick's odometry pose (the robot was placed there: a known pose)."""
        self._restart_pending = True

    def update(self, tick: TickInput) -> None:
        """One tick: the filter predicts with odometry and weighs each new scan once the robot moved."""
        if self._restart_pending:
            self._filter, self._restart_pending = self._filter_at(tick.odometry.pose, self._field), False
        self._filter.track(tick)

    def believed_pose(self, odometry: Pose2D) -> Pose2D | None:
        """The tracked pose now, or None before the first scan or after losing track (odometry it is, then)."""
        return self._filter.believed_pose(odometry)

    def _filter_at(self, start: Pose2D, field: np.ndarray | None) -> Localization:
        own = Perception()
        own.environment = self._model
        return Localization(start.x_m, start.y_m, start.theta_rad, START_SPREAD_M, START_SPREAD_RAD,
                            TRACKER_PARTICLES, own, self._seed, publish=False, field=field)
