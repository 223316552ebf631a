"""The localization skill: a particle filter (Monte Carlo localization) against the environment model."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from skill_server.errors import NoMap
from skill_server.goals import EventKind, GoalFeedback
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.geometry import Pose2D, wrap_angle
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for
from skill_server.skills.global_search import FieldLookup
from skill_server.skills.perception import LocalizationEstimate, Perception
from skill_server.skills.relocalization import Relocalizer
from skill_server.skills.scan_matching import compose, distance_field, relative, signed_point_field

__all__ = ["LOCALIZATION", "Localization", "LocalizationEstimate", "compose", "distance_field", "relative"]

LOCALIZATION = "localization"
BEAM_STEP = 6  # every 6th laser beam: 31 beams are plenty for a likelihood field
HIT_SIGMA_M = 0.05
RANDOM_ECHO_LIKELIHOOD = 0.05  # per beam, relative to a perfect hit's 1.0
LIKELIHOOD_TEMPER = 3.0
FIELD_CAP_CELLS = 12
CONVERGED_STD_M, CONVERGED_STD_RAD = 0.06, 0.05
FIELD_REFRESH_S = 2.0
UPDATE_MIN_M, UPDATE_MIN_RAD = 0.03, 0.03  # motion between two updates once converged
# "Converged" needs evidence, not only a tight cloud: a cloud can collapse onto a wrong pose (a guess far off, a
# heading 45-145 degrees wrong) where few echoes meet the map. At the first collapse onto a wrong pose 3-42 % of
# the echoes lay within 3 sigma of the map's surfaces; onto the true pose, 100 %.
CONVERGED_MIN_FIT = 0.8
# A converged estimate is given up when its fit stays below this for LOST_AFTER_UPDATES updates in a row.
LOST_FIT, LOST_AFTER_UPDATES = 0.5, 5
FOUND_SPREAD_M, FOUND_SPREAD_RAD = 0.15, 0.1  # the cloud restarts this wide at a place the search found
MAP_ERROR_GAIN = 0.5  # reported std per axis includes this times the echoes' residual RMS (map mismatch)
MAP_ERROR_LEVER_M = 2.0  # typical beam length [m]: turns the residual into a heading uncertainty


def localization_description() -> SkillDescription:
    """The schema of localization."""
    return SkillDescription(
        name=LOCALIZATION,
        title="Localization",
        help=(
            "Perceptive skill: estimates the robot's pose against the environment model with a particle filter "
            "(sets of poses whose laser readings best match the map), starting from a guess. While it runs, the "
            "motor skills steer by its estimate instead of raw odometry. Needs a map (Environment modelling). If "
            "the guess is wrong or unknown, it searches the whole map with the scans of a turn or a short drive."
        ),
        parameters=(
            ParameterSchema("initial_x_m", ParameterType.DOUBLE, "m", -50.0, 50.0, 0.0, "Guess of x."),
            ParameterSchema("initial_y_m", ParameterType.DOUBLE, "m", -50.0, 50.0, 0.0, "Guess of y."),
            ParameterSchema("initial_theta_rad", ParameterType.DOUBLE, "rad", -math.pi, math.pi, 0.0,
                            "Guess of the heading."),
            ParameterSchema("initial_spread_m", ParameterType.DOUBLE, "m", 0.01, 2.0, 0.5,
                            "How far off the guess may be (standard deviation of the first particles)."),
            ParameterSchema("initial_spread_rad", ParameterType.DOUBLE, "rad", 0.01, math.pi, 0.2,
                            "How far off the heading guess may be."),
            ParameterSchema("particle_count", ParameterType.INT, "", 50, 5000, 400, "Number of particles."),
        ),
    )


class Localization(SkillController):
    """Monte Carlo localization with a likelihood field; motion noise grows with the odometry increment."""

    motor = False
    skill_class = "perceptive"
    estimates_pose = True
    uses_map = True

    def __init__(self, initial_x_m: float, initial_y_m: float, initial_theta_rad: float, initial_spread_m: float,
                 initial_spread_rad: float, particle_count: int, perception: Perception, seed: int = 7,
                 publish: bool = True, field: np.ndarray | None = None) -> None:
        super().__init__()
        self._publish = publish  # False: nobody watches (the pose tracking), so no estimate is built for streams
        model = perception.environment
        if model is None or not model.occupied().any():
            raise NoMap("no environment model yet: run environment_modelling first")
        self._perception = perception
        self._model = model
        self._rng = np.random.default_rng(seed)
        n = particle_count
        self._particles = np.column_stack([
            self._rng.normal(initial_x_m, initial_spread_m, n),
            self._rng.normal(initial_y_m, initial_spread_m, n),
            self._rng.normal(initial_theta_rad, initial_spread_rad, n),
        ])
        self._weights = np.full(n, 1.0 / n)
        self._field: np.ndarray | None = field  # a field computed for this model already (the pose tracking's)
        self._field_version = model.version if field is not None else -1
        self._field_s = -math.inf
        self._last_odometry: Pose2D | None = None
        self._estimate = Pose2D(initial_x_m, initial_y_m, initial_theta_rad)
        self._estimate_odometry: Pose2D | None = None  # odometry reading when the estimate was made
        self._converged = False
        self._poor_fits = 0  # updates in a row whose fit was below LOST_FIT
        self._std = (initial_spread_m, initial_spread_m, initial_spread_rad)
        self._published: LocalizationEstimate | None = None
        self._beams: tuple[np.ndarray, np.ndarray] | None = None  # the last update's beams (ranges, angles)
        guess = Pose2D(initial_x_m, initial_y_m, initial_theta_rad)
        self._relocalizer = Relocalizer(initial_spread_m, guess)  # the evidence while not trusted
        self.searches_whole_map = True  # the pose tracking turns it off while the localization skill searches
        perception.localizer = self

    def believed_pose(self, odometry: Pose2D) -> Pose2D | None:
        """The estimate moved on by the odometry since it was made; None until converged."""
        if not self._converged or self._estimate_odometry is None:
            return None
        return compose(self._estimate, relative(self._estimate_odometry, odometry))

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Tracks (see track) and reports the estimate as feedback."""
        self.track(tick)
        std_x, std_y, std_theta = self._std
        state = "tracking" if self._converged else "searching" if self._relocalizer.searching else "converging"
        return 0.0, 0.0, None, feedback_for(
            tick, state, 1.0 if self._converged else 0.0,
            math.hypot(std_x, std_y), std_theta, std_x_m=std_x, std_y_m=std_y, std_theta_rad=std_theta,
            estimate_x_m=self._estimate.x_m, estimate_y_m=self._estimate.y_m,
            estimate_theta_rad=self._estimate.theta_rad, **self._relocalizer.figures,
        )

    def track(self, tick: TickInput) -> None:
        """Predict with odometry, weigh by the scan, resample when the weights degenerate."""
        odometry = tick.odometry.pose
        if self._last_odometry is None:
            self._last_odometry = odometry
        delta = relative(self._last_odometry, odometry)
        # Like AMCL, a converged filter waits for some motion: re-weighing the same view of a standing robot
        # only makes it overconfident, and it is most of the skills' cost in fast mode.
        moved = (not self._converged or math.hypot(delta.x_m, delta.y_m) >= UPDATE_MIN_M
                 or abs(delta.theta_rad) >= UPDATE_MIN_RAD)
        if tick.new_scan and moved:
            started = time.perf_counter()
            self._predict(delta)
            self._last_odometry = odometry
            self._refresh_field(tick.sim_time_s)
            self._weigh(tick)
            if not self._converged and self._beams is not None:
                self._relocalizer.gather(odometry, np.asarray(tick.laser_ranges_m), tick.sensors.laser_angles_rad,
                                         tick.sensors.laser.max_range_m)
            self._summarise(odometry, (time.perf_counter() - started) * 1000.0)
            self._relocalize(tick)
        elif self._publish and self._published is not None and self._estimate_odometry is not None:
            # Between updates (every tick, not only on scans) readers get the estimate moved on by the latest
            # odometry, so it does not trail the robot by up to a scan period (2 cm at 0.3 m/s).
            pose = compose(self._estimate, relative(self._estimate_odometry, odometry))
            self._published = replace(self._published, pose=pose, odometry=odometry)
            self._perception.published_estimate = self._published

    def stop(self) -> None:
        """The motor skills go back to odometry."""
        if self._perception.localizer is self:
            self._perception.localizer = None
            self._perception.published_estimate = None

    @property
    def field(self) -> np.ndarray:
        """The likelihood field of the map (distance to the surfaces), computed now if it was not yet."""
        self._refresh_field(0.0)
        assert self._field is not None
        return self._field

    def _lookup(self) -> FieldLookup:
        assert self._field is not None
        return FieldLookup(self._field, self._model.origin_m, self._model.resolution_m)

    def _relocalize(self, tick: TickInput) -> None:
        """While the estimate is not trusted: gathers the scans and, once the guess has failed, searches the whole
        map; the cloud restarts at a place found."""
        if self._converged:
            self._relocalizer.trusted()
            return
        if not self.searches_whole_map:
            return
        step = self._relocalizer.after_update(self._lookup(), self._model.log_odds < 0, tick.odometry.pose,
                                              self._estimate)
        if step.announcement:
            self.announce(EventKind.STEP_STARTED, step.announcement)
        if step.found is not None:
            pose, n = step.found, len(self._particles)
            self._particles = np.column_stack([
                self._rng.normal(pose.x_m, FOUND_SPREAD_M, n), self._rng.normal(pose.y_m, FOUND_SPREAD_M, n),
                self._rng.normal(pose.theta_rad, FOUND_SPREAD_RAD, n)])
            self._weights = np.full(n, 1.0 / n)

    def _predict(self, delta: Pose2D) -> None:
        n = len(self._particles)
        step_m = math.hypot(delta.x_m, delta.y_m)
        # Noise proportional to the motion, plus a floor that keeps the cloud from collapsing when still.
        trans_std = 0.04 * step_m + 0.002
        rot_std = 0.04 * abs(delta.theta_rad) + 0.01 * step_m + 0.002
        dx = delta.x_m + self._rng.normal(0.0, trans_std, n)
        dy = delta.y_m + self._rng.normal(0.0, trans_std, n)
        theta = self._particles[:, 2]
        self._particles[:, 0] += dx * np.cos(theta) - dy * np.sin(theta)
        self._particles[:, 1] += dx * np.sin(theta) + dy * np.cos(theta)
        self._particles[:, 2] = theta + delta.theta_rad + self._rng.normal(0.0, rot_std, n)

    def _refresh_field(self, sim_time_s: float) -> None:
        if self._field is not None and (self._model.version == self._field_version
                                        or sim_time_s - self._field_s < FIELD_REFRESH_S):
            return
        occupied = self._model.occupied()
        if not self._model.surfaces_on_cell_edges:
            # A map from readings: signed distance to the echoes' sub-cell points, negative behind a surface (seen
            # from the free side), so bilinear interpolation puts the zero on the surface, not on cell centres.
            self._field = signed_point_field(self._model, FIELD_CAP_CELLS)
            self._field_version, self._field_s = self._model.version, sim_time_s
            return
        field = distance_field(occupied, FIELD_CAP_CELLS)
        if self._model.surfaces_on_cell_edges:
            # Surfaces on cell edges: a signed distance to them (negative inside), zero exactly on the edge once
            # interpolated, so echoes are pulled onto the surface from both sides instead of sinking into walls.
            field = np.where(occupied, 0.5 - distance_field(~occupied, FIELD_CAP_CELLS), field - 0.5)
        self._field = field * self._model.resolution_m
        self._field_version, self._field_s = self._model.version, sim_time_s

    def _weigh(self, tick: TickInput) -> None:
        assert self._field is not None
        ranges_m = np.asarray(tick.laser_ranges_m)[::BEAM_STEP]
        angles = tick.sensors.laser_angles_rad[::BEAM_STEP]
        valid = ranges_m < tick.sensors.laser.max_range_m - 1e-6
        ranges_m, angles = ranges_m[valid], angles[valid]
        if ranges_m.size < 5:
            return
        self._beams = (ranges_m, angles)
        p = self._particles
        world = p[:, 2:3] + angles[None, :]
        xs = p[:, 0:1] + ranges_m[None, :] * np.cos(world)
        ys = p[:, 1:2] + ranges_m[None, :] * np.sin(world)
        distance_m = self._field_at(xs, ys)
        # Each beam: a Gaussian around the map's surfaces plus a floor for things the map lacks (people, boxes
        # moved), so one unexplained echo cannot outvote the rest; tempered because beams are not independent.
        beam_likelihood = np.exp(-0.5 * (distance_m / HIT_SIGMA_M) ** 2) + RANDOM_ECHO_LIKELIHOOD
        log_likelihood = np.sum(np.log(beam_likelihood), axis=1) / LIKELIHOOD_TEMPER
        log_weights = np.log(self._weights + 1e-300) + log_likelihood
        log_weights -= log_weights.max()
        weights = np.exp(log_weights)
        self._weights = weights / weights.sum()
        if 1.0 / np.sum(self._weights**2) < 0.5 * len(self._weights):
            self._resample()

    def _field_at(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Distance [m] to the nearest occupied cell, bilinear between cell centres (no 5 cm steps, no bias)."""
        assert self._field is not None
        model = self._model
        fx = np.clip((xs - model.origin_m) / model.resolution_m - 0.5, 0.0, model.size - 1.001)
        fy = np.clip((ys - model.origin_m) / model.resolution_m - 0.5, 0.0, model.size - 1.001)
        ix, iy = fx.astype(np.int64), fy.astype(np.int64)
        ax, ay = fx - ix, fy - iy
        field = self._field
        return ((1 - ax) * ((1 - ay) * field[ix, iy] + ay * field[ix, iy + 1])
                + ax * ((1 - ay) * field[ix + 1, iy] + ay * field[ix + 1, iy + 1]))

    def _fit(self, pose: Pose2D) -> tuple[float, float]:
        """How the last scan's echoes placed at pose meet the map: the RMS distance [m] of those within 3 sigma of
        a surface (the others are explained by the random-echo floor) and the fraction of echoes that are."""
        if self._beams is None or self._field is None:
            return 0.0, 0.0
        ranges_m, angles = self._beams
        world = pose.theta_rad + angles
        gaps = self._field_at(pose.x_m + ranges_m * np.cos(world), pose.y_m + ranges_m * np.sin(world))
        inliers = gaps[np.abs(gaps) < 3.0 * HIT_SIGMA_M]
        rms = float(np.sqrt(np.mean(inliers**2))) if inliers.size else 3.0 * HIT_SIGMA_M
        return rms, inliers.size / max(1, gaps.size)

    def _particle_std(self, x: float, y: float) -> tuple[float, float]:
        w, p = self._weights, self._particles
        return math.sqrt(float(np.sum(w * (p[:, 0] - x) ** 2))), math.sqrt(float(np.sum(w * (p[:, 1] - y) ** 2)))

    def _resample(self) -> None:
        n = len(self._weights)
        positions = (self._rng.random() + np.arange(n)) / n
        indices = np.minimum(np.searchsorted(np.cumsum(self._weights), positions), n - 1)
        self._particles = self._particles[indices]
        self._weights = np.full(n, 1.0 / n)

    def _summarise(self, odometry: Pose2D, duration_ms: float) -> None:
        w, p = self._weights, self._particles
        x, y = float(np.sum(w * p[:, 0])), float(np.sum(w * p[:, 1]))
        theta = math.atan2(float(np.sum(w * np.sin(p[:, 2]))), float(np.sum(w * np.cos(p[:, 2]))))
        std_x = math.sqrt(float(np.sum(w * (p[:, 0] - x) ** 2)))
        std_y = math.sqrt(float(np.sum(w * (p[:, 1] - y) ** 2)))
        std_theta = math.sqrt(float(np.sum(w * np.angle(np.exp(1j * (p[:, 2] - theta))) ** 2)))
        self._estimate, self._estimate_odometry = Pose2D(x, y, wrap_angle(theta)), odometry
        residual_m, fit = self._fit(self._estimate)
        self._poor_fits = self._poor_fits + 1 if fit < LOST_FIT else 0
        tight = max(std_x, std_y) < CONVERGED_STD_M and std_theta < CONVERGED_STD_RAD
        converged = tight and fit >= CONVERGED_MIN_FIT
        if converged and not self._converged:
            converged = self._relocalizer.confirms(self._lookup(), self._model.log_odds < 0,
                                                   Pose2D(x, y, wrap_angle(theta)), odometry)
        if converged and not self._converged:
            self.announce(EventKind.CONVERGED, f"converged at ({x:.2f}, {y:.2f}) m, std {max(std_x, std_y):.3f} m, "
                                               f"{fit:.0%} of the echoes on the map")
        was_converged = self._converged
        self._converged = converged or (self._converged and max(std_x, std_y) < 2 * CONVERGED_STD_M
                                        and self._poor_fits < LOST_AFTER_UPDATES)
        if was_converged and not self._converged:
            self._relocalizer.lost()
        # The cloud's spread only measures how well poses are told apart by this map; it says nothing about the map
        # being wrong (a missed or moved object, surfaces off by part of a cell), which shifts every particle alike.
        # The echoes' residual at the estimate measures that mismatch, and is added as a correlated error term.
        std_x, std_y = math.hypot(std_x, MAP_ERROR_GAIN * residual_m), math.hypot(std_y, MAP_ERROR_GAIN * residual_m)
        std_theta = math.hypot(std_theta, MAP_ERROR_GAIN * residual_m / MAP_ERROR_LEVER_M)
        self._std = (std_x, std_y, std_theta)
        if not self._publish:
            return
        sample = np.column_stack([p[:: max(1, len(p) // 200)], w[:: max(1, len(p) // 200)]])
        self._published = LocalizationEstimate(
            self._estimate, std_x, std_y, std_theta, self._converged, duration_ms,
            tuple(map(tuple, sample.tolist())),  # tolist first: a per-element loop costs 0.3 ms per update
            odometry, residual_m, math.hypot(*self._particle_std(x, y)),
        )
        self._perception.published_estimate = self._published
