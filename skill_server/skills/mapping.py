"""The environment_modelling skill: an occupancy grid of the lab from laser (and sonar) readings."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skill_server.goals import GoalFeedback, GoalStatus
from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import SceneSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for
from skill_server.skills.scan_matching import ScanMatcher, compose, relative
from skill_server.skills.schema import ParameterSchema, ParameterType, SkillDescription

ENVIRONMENT_MODELLING = "environment_modelling"
HIT_LOG_ODDS, FREE_LOG_ODDS, CLAMP_LOG_ODDS = 0.9, -0.35, 6.0
FREE_RANGE_M = 6.0  # beyond this, free space along a beam is not carved (long beams graze too much)
PUBLISH_PERIOD_S = 1.0


@dataclass(frozen=True)
class PublishedGrid:
    """An immutable copy of the grid for GetMap: percent occupancy per cell, 255 where unknown."""

    resolution_m: float
    origin_x_m: float
    origin_y_m: float
    width_cells: int
    height_cells: int
    cells: bytes  # row-major from (0, 0), x fastest
    scans_integrated: int
    sim_time_s: float


class EnvironmentModel:
    """Log-odds occupancy grid in the lab frame; cells are indexed [ix, iy]."""

    def __init__(self, resolution_m: float = 0.05, half_extent_m: float = 6.0) -> None:
        self.resolution_m = resolution_m
        self.origin_m = -half_extent_m
        self.size = int(round(2 * half_extent_m / resolution_m))
        self.log_odds = np.zeros((self.size, self.size), dtype=np.float32)
        self.scans_integrated = 0
        self.version = 0
        self.surfaces_on_cell_edges = False  # True once a floor plan is drawn in (see add_floor_plan)
        # Where the laser's echoes fell inside each cell (sums, for their mean) and the direction they were seen
        # from: sub-cell surface points for scan matching and a signed distance field for localization.
        self.hit_sum_m = np.zeros((self.size, self.size, 2))
        self.hit_count = np.zeros((self.size, self.size))
        self.view_sum = np.zeros((self.size, self.size, 2))

    def integrate_laser(self, tick: TickInput, beam_step: int = 2, pose: Pose2D | None = None) -> None:
        """Carves free space along the beams and marks their echoes, at pose (default: the believed pose)."""
        pose = pose or tick.pose
        ranges_m = np.asarray(tick.laser_ranges_m)[::beam_step]
        angles_rad = tick.sensors.laser_angles_rad[::beam_step] + pose.theta_rad
        echoed = ranges_m < tick.sensors.laser.max_range_m - 1e-6
        res = self.resolution_m
        steps = np.arange(res, FREE_RANGE_M, res)
        free_len = np.minimum(ranges_m - res, FREE_RANGE_M)
        along = steps[None, :] < free_len[:, None]
        fx = pose.x_m + steps[None, :] * np.cos(angles_rad)[:, None]
        fy = pose.y_m + steps[None, :] * np.sin(angles_rad)[:, None]
        self._add(fx[along], fy[along], FREE_LOG_ODDS)
        hx = pose.x_m + ranges_m[echoed] * np.cos(angles_rad[echoed])
        hy = pose.y_m + ranges_m[echoed] * np.sin(angles_rad[echoed])
        self._add(hx, hy, HIT_LOG_ODDS)
        self._add_points(hx, hy, -np.cos(angles_rad[echoed]), -np.sin(angles_rad[echoed]))
        np.clip(self.log_odds, -CLAMP_LOG_ODDS, CLAMP_LOG_ODDS, out=self.log_odds)
        self.scans_integrated += 1
        self.version += 1

    def add_floor_plan(self, scene: SceneSpec) -> None:
        """Draws the lab's floor plan (walls and furniture as built) in: obstacles occupied, the floor free."""
        centers = self.origin_m + (np.arange(self.size) + 0.5) * self.resolution_m
        xs, ys = np.meshgrid(centers, centers, indexing="ij")
        # A cell is an obstacle's if its centre lies inside it, so drawn surfaces fall on cell edges (the lab's
        # furniture is laid out on the 5 cm grid); readings put theirs mid-cell instead.
        occupied = np.zeros_like(self.log_odds, dtype=bool)
        for box in scene.boxes:
            c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
            dx, dy = xs - box.center_x_m, ys - box.center_y_m
            occupied |= (np.abs(c * dx + s * dy) <= box.half_x_m) & (np.abs(-s * dx + c * dy) <= box.half_y_m)
        for cylinder in scene.cylinders:
            occupied |= np.hypot(xs - cylinder.center_x_m, ys - cylinder.center_y_m) <= cylinder.radius_m
        floor = (np.abs(xs) <= scene.floor_half_x_m) & (np.abs(ys) <= scene.floor_half_y_m)
        self.log_odds[floor] = np.minimum(self.log_odds[floor], -CLAMP_LOG_ODDS)
        self.log_odds[occupied] = CLAMP_LOG_ODDS
        self.surfaces_on_cell_edges = True
        self.version += 1

    def integrate_sonar(self, tick: TickInput, pose: Pose2D | None = None) -> None:
        """Marks each sonar's echo on its axis (a cone is too wide to carve free space reliably)."""
        pose = pose or tick.pose
        ranges_m = np.asarray(tick.sonar_ranges_m)
        mounts = np.asarray(tick.sensors.sonar_mount_rad) + pose.theta_rad
        echoed = ranges_m < min(tick.sensors.sonar_max_range_m - 1e-6, 1.5)  # near echoes are sharp enough
        reach = ranges_m[echoed] + tick.sensors.sonar_mount_radius_m
        self._add(pose.x_m + reach * np.cos(mounts[echoed]), pose.y_m + reach * np.sin(mounts[echoed]),
                  0.3 * HIT_LOG_ODDS)

    def _add(self, xs: np.ndarray, ys: np.ndarray, amount: float) -> None:
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        flat = np.unique(ix[inside] * self.size + iy[inside])  # each cell once per scan, like a ray caster
        self.log_odds.reshape(-1)[flat] += amount

    def _add_points(self, xs: np.ndarray, ys: np.ndarray, view_x: np.ndarray, view_y: np.ndarray) -> None:
        ix = np.floor((xs - self.origin_m) / self.resolution_m).astype(np.int64)
        iy = np.floor((ys - self.origin_m) / self.resolution_m).astype(np.int64)
        inside = (ix >= 0) & (ix < self.size) & (iy >= 0) & (iy < self.size)
        ix, iy = ix[inside], iy[inside]
        np.add.at(self.hit_sum_m, (ix, iy, 0), xs[inside])
        np.add.at(self.hit_sum_m, (ix, iy, 1), ys[inside])
        np.add.at(self.hit_count, (ix, iy), 1.0)
        np.add.at(self.view_sum, (ix, iy, 0), view_x[inside])
        np.add.at(self.view_sum, (ix, iy, 1), view_y[inside])

    def surface_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Occupied cells holding echoes: their indices (n x 2), mean echo point [m] and unit normal toward the free
        side (the mean direction the echoes were seen from)."""
        cells = np.argwhere(self.occupied() & (self.hit_count > 0))
        ix, iy = cells[:, 0], cells[:, 1]
        points = self.hit_sum_m[ix, iy] / self.hit_count[ix, iy][:, None]
        normals = self.view_sum[ix, iy]
        normals = normals / np.maximum(np.linalg.norm(normals, axis=1), 1e-9)[:, None]
        return cells, points, normals

    def occupied(self) -> np.ndarray:
        """Cells more likely occupied than not, by a margin."""
        return self.log_odds > 0.5

    def publish(self, sim_time_s: float) -> PublishedGrid:
        """An immutable copy for readers in other threads."""
        probability = 1.0 / (1.0 + np.exp(-self.log_odds))
        percent = np.round(probability * 100).astype(np.uint8)
        percent[self.log_odds == 0] = 255
        return PublishedGrid(self.resolution_m, self.origin_m, self.origin_m, self.size, self.size,
                             percent.T.tobytes(), self.scans_integrated, sim_time_s)


def environment_modelling_description() -> SkillDescription:
    """The schema of environment_modelling."""
    return SkillDescription(
        name=ENVIRONMENT_MODELLING,
        title="Environment modelling",
        help=(
            "Perceptive skill: builds an occupancy grid of the lab from the laser (and near sonar echoes) while "
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

    def __init__(self, use_sonar: bool, restart: bool, duration_s: float, perception: object,
                 use_floor_plan: bool = False, align_scans: bool = True) -> None:
        super().__init__()
        self._perception = perception
        if restart or getattr(perception, "environment", None) is None:
            perception.environment = EnvironmentModel()  # type: ignore[attr-defined]
        self._model: EnvironmentModel = perception.environment  # type: ignore[attr-defined]
        floor_plan = getattr(perception, "floor_plan", None)
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
        if tick.new_scan and moved:
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
            self._perception.published_map = self._model.publish(tick.sim_time_s)  # type: ignore[attr-defined]
        known = float(np.count_nonzero(self._model.log_odds)) * self._model.resolution_m**2
        return 0.0, 0.0, outcome, feedback_for(tick, "mapping", 0.0, scans=float(self._model.scans_integrated),
                                               known_area_m2=known)

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
        self._perception.published_map = self._model.publish(self._last_time())  # type: ignore[attr-defined]

    def _last_time(self) -> float:
        return self.last_feedback.sim_time_s
