"""The environment_modelling skill: an occupancy grid of the lab from laser (and sonar) readings."""

from __future__ import annotations

import math

import numpy as np

from skill_server.goals import GoalFeedback, GoalStatus
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.geometry import Pose2D
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for
from skill_server.skills.environment_model import FREE_RANGE_M, EnvironmentModel
from skill_server.skills.perception import Perception
from skill_server.skills.scan_matching import ScanMatcher, compose, relative

ENVIRONMENT_MODELLING = "environment_modelling"
PUBLISH_PERIOD_S = 1.0


def environment_modelling_description() -> SkillDescription:
    """The schema of environment_modelling."""
    return SkillDescription(
        name=ENVIRONMENT_MODELLING,
        title="Environment modelling",
        help=(
            "Deliberative skill: builds an occupancy grid of the lab from the laser (and near sonar echoes) while "
            "the robot moves. Each scan is placed at the pose the robot believes (the localization estimate when "
            "localization runs, else odometry), corrected by matching the scan to the map built so far. Drive a "
            "tour (one lap of wall following) for a whole map. The floor-plan option is a teaching aid: it draws the "
            "lab as built first. The map is kept after the skill ends; GetMap returns it."
        ),
        parameters=(
            ParameterSchema("use_sonar", ParameterType.BOOL, "", 0.0, 1.0, 1.0,
                            "Also mark near sonar echoes (behind the laser's half-plane)."),
            ParameterSchema("restart", ParameterType.BOOL, "", 0.0, 1.0, 0.0,
                            "Start from an empty map instead of extending the one kept."),
            ParameterSchema("use_floor_plan", ParameterType.BOOL, "", 0.0, 1.0, 0.0,
                            "Teaching aid: start from the lab's floor plan (walls and furniture as built), then add "
                            "readings."),
            ParameterSchema("align_scans", ParameterType.BOOL, "", 0.0, 1.0, 1.0,
                            "Correct the pose by matching each scan to the map built so far before adding it "
                            "(SLAM-lite), so the map does not inherit odometry drift."),
            ParameterSchema("duration_s", ParameterType.DOUBLE, "s", 0.0, 3600.0, 0.0,
                            "Stop and succeed after this long (0 = until cancelled)."),
        ),
    )


class EnvironmentModelling(SkillController):
    """Integrates scans when the robot has moved enough that a scan adds something."""

    motor = False
    skill_class = "deliberative"  # the environment modeller, a deliberative module in the paper
    uses_map = True

    def __init__(self, use_sonar: bool, restart: bool, duration_s: float, perception: Perception,
                 use_floor_plan: bool = False, align_scans: bool = True) -> None:
        super().__init__()
        self._perception = perception
        if restart or perception.environment is None:
            perception.environment = EnvironmentModel()
        self._model: EnvironmentModel = perception.environment
        floor_plan = perception.floor_plan
        if use_floor_plan and floor_plan is not None:
            self._model.add_floor_plan(floor_plan)
        self._use_sonar = bool(use_sonar)
        self._align = bool(align_scans)
        self._matcher: ScanMatcher | None = None
        self._track: Pose2D | None = None  # the pose the map was last extended from, in the map's frame
        self._track_source: Pose2D | None = None  # the believed pose (odometry or localization) at that moment
        self._track_kind = ""
        self.corrections = 0  # scans whose pose the matcher corrected
        self._duration_s = duration_s
        self._started_s: float | None = None
        self._last_pose: tuple[float, float, float] | None = None
        self._published_s = -math.inf

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Adds the scan if the robot moved 5 cm or turned 3 degrees since the last one."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        pose = tick.pose
        moved = self._last_pose is None or (
            math.hypot(pose.x_m - self._last_pose[0], pose.y_m - self._last_pose[1]) > 0.05
            or abs(math.remainder(pose.theta_rad - self._last_pose[2], 2 * math.pi)) > math.radians(3)
        )
        if tick.new_scan and moved and not self._lost(tick):
            at = self._aligned_pose(tick) if self._align else pose
            self._model.integrate_laser(tick, pose=at)
            if self._use_sonar:
                self._model.integrate_sonar(tick, pose=at)
            self._last_pose = (pose.x_m, pose.y_m, pose.theta_rad)
        outcome = None
        if self._duration_s > 0 and tick.sim_time_s - self._started_s >= self._duration_s:
            outcome = Outcome(GoalStatus.SUCCEEDED, "", f"mapped for {self._duration_s:g} s, "
                              f"{self._model.scans_integrated} scans")
        if outcome is not None or tick.sim_time_s - self._published_s >= PUBLISH_PERIOD_S:
            self._published_s = tick.sim_time_s
            self._perception.published_map = self._model.publish(tick.sim_time_s)
        known = float(np.count_nonzero(self._model.log_odds)) * self._model.resolution_m**2
        return 0.0, 0.0, outcome, feedback_for(tick, "mapping", 0.0, scans=float(self._model.scans_integrated),
                                               known_area_m2=known)

    def _lost(self, tick: TickInput) -> bool:
        """Whether the robot is looking for where it is: a localization skill runs and trusts no pose yet, nor does
        the pose tracking, so the skills steer by bare odometry. A scan drawn then lands where odometry believes the
        robot is; after a kidnapping that drew the place the robot was carried to over the one it was carried from
        (100 scans of a turn flip the floor plan's cells), and localization then converged there, or found two
        places forever. The map waits until a pose is trusted again."""
        return self._perception.localizer is not None and tick.pose_source == "odometry"

    def _aligned_pose(self, tick: TickInput) -> Pose2D:
        """Where to place this scan: the track moved on by the believed pose's increment, fitted to the map."""
        if self._track is None or self._track_source is None or tick.pose_source != self._track_kind:
            guess = tick.pose  # first scan, or localization took over (its estimate is in the map's frame)
        else:
            guess = compose(self._track, relative(self._track_source, tick.pose))
        model = self._model
        if self._matcher is None:
            self._matcher = ScanMatcher(model.origin_m, model.resolution_m, model.size)
        self._matcher.update(model)
        at = guess
        if self._matcher.has_map:
            ranges_m = np.asarray(tick.laser_ranges_m)[::2]
            angles_rad = tick.sensors.laser_angles_rad[::2]
            valid = ranges_m < min(tick.sensors.laser.max_range_m - 1e-6, FREE_RANGE_M)
            result = self._matcher.match(guess, ranges_m[valid], angles_rad[valid])
            if result.accepted:
                at = result.pose
                self.corrections += 1
        self._track, self._track_source, self._track_kind = at, tick.pose, tick.pose_source
        return at

    def stop(self) -> None:
        """Publishes the final map."""
        self._perception.published_map = self._model.publish(self._last_time())

    def _last_time(self) -> float:
        return self.last_feedback.sim_time_s
