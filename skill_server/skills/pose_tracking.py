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
from skill_server.skills.scan_matching import compose, relative

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
        self._adopted: tuple[Pose2D, Pose2D] | None = None  # a pose trusted elsewhere, and odometry then
        self._lost = False  # carried off: nothing tracked until a pose is known again

    def restart(self) -> None:
        """Starts again at the next tick's odometry pose (the robot was placed there: a known pose)."""
        self._restart_pending, self._lost = True, False

    def lose(self) -> None:
        """The robot was carried off without being told: its pose is unknown until the localization skill finds it
        (adopt) or it is placed again. Restarted at odometry's belief instead, the tight cloud converged at a place
        looking like the one the robot was carried to (4 of 8 kidnappings to the room's mirror place), the skills
        steered by it and the environment model drew the search's scans there (133-403 cells of the floor plan
        flipped)."""
        self._lost, self._restart_pending, self._adopted = True, False, None

    def adopt(self, pose: Pose2D, odometry: Pose2D) -> None:
        """Starts again at pose (at that odometry reading), which the localization skill trusts while this tracker
        has lost track: after a kidnapping, the skills go on steering by the place found once the skill stops."""
        self._adopted, self._lost = (pose, odometry), False

    def update(self, tick: TickInput, defer_search: bool = False) -> None:
        """One tick: the filter predicts with odometry and weighs each new scan once the robot moved. With
        defer_search (a localization skill runs and searches the map itself), a lost tracker does not search the
        whole map too: two searches doubled the loop's work."""
        if self._lost:
            return
        if self._restart_pending:
            self._filter, self._restart_pending = self._filter_at(tick.odometry.pose, self._field), False
        if self._adopted is not None:
            pose, odometry = self._adopted
            self._filter = self._filter_at(compose(pose, relative(odometry, tick.odometry.pose)), self._field)
            self._adopted = None
        self._filter.searches_whole_map = not defer_search
        self._filter.track(tick)

    def believed_pose(self, odometry: Pose2D) -> Pose2D | None:
        """The tracked pose now, or None before the first scan or after losing track (odometry it is, then)."""
        return None if self._lost else self._filter.believed_pose(odometry)

    def _filter_at(self, start: Pose2D, field: np.ndarray | None) -> Localization:
        own = Perception()
        own.environment = self._model
        return Localization(start.x_m, start.y_m, start.theta_rad, START_SPREAD_M, START_SPREAD_RAD,
                            TRACKER_PARTICLES, own, self._seed, publish=False, field=field)
