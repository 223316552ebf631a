"""Maps from readings alone: scan matching keeps odometry drift out of the map, and localization works on it."""

from __future__ import annotations

import math

import numpy as np
from skill_sim_helpers import TOKEN

from skill_server.sequencer import attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World
from skill_server.skills.base import TickInput
from skill_server.skills.environment_model import EnvironmentModel
from skill_server.skills.scan_matching import ScanMatcher, compose, relative, signed_point_field


def _tick_at(world: World, sequencer: object, pose: Pose2D) -> TickInput:
    world.set_pose(pose)
    snapshot = world.snapshot
    return TickInput(snapshot.sim_time_s, 1 / 60, snapshot.odometry, snapshot.sonar_ranges_m,
                     snapshot.laser_ranges_m, True, snapshot.ground_truth, "odometry", world.spec,
                     sequencer.sensors)


def test_the_scan_matcher_pulls_a_wrong_guess_back_onto_the_map() -> None:
    with World("lab", realtime=False) as world:
        sequencer = attach_sequencer(world)
        model = EnvironmentModel()
        model.integrate_laser(_tick_at(world, sequencer, Pose2D(0.0, 0.0, 0.0)))
        matcher = ScanMatcher(model.origin_m, model.resolution_m, model.size)
        matcher.update(model)
        truth = Pose2D(0.1, 0.05, 0.08)
        tick = _tick_at(world, sequencer, truth)
        ranges = np.asarray(tick.laser_ranges_m)[::2]
        angles = sequencer.sensors.laser_angles_rad[::2]
        seen = ranges < 6.0
        result = matcher.match(Pose2D(0.14, 0.02, 0.1), ranges[seen], angles[seen])
        assert result.accepted and result.inliers > 50
        assert truth.distance_to(result.pose) < 0.01
        assert abs(math.remainder(result.pose.theta_rad - truth.theta_rad, 2 * math.pi)) < math.radians(0.5)


def test_the_signed_field_changes_sign_on_the_surface() -> None:
    with World("lab", realtime=False) as world:
        sequencer = attach_sequencer(world)
        model = EnvironmentModel()
        model.integrate_laser(_tick_at(world, sequencer, Pose2D(0.0, 0.0, 0.0)))  # facing the east wall at x = 4
        field = signed_point_field(model, 6)
        iy = int((0.0 - model.origin_m) / model.resolution_m)
        centre = lambda x_m: int((x_m - model.origin_m) / model.resolution_m)  # noqa: E731
        assert field[centre(3.87), iy] > 0.1 and field[centre(4.13), iy] < -0.1
        # Cell centres at 3.975 and 4.025 straddle the surface with opposite signs and equal magnitudes (the nearest
        # echo may lie a little aside), so the field interpolates to zero on the surface, not on a cell centre.
        front, behind = field[centre(3.97), iy], field[centre(4.02), iy]
        assert 0.0 < front < 0.05 and -0.05 < behind < 0.0 and abs(front + behind) < 0.005


def test_compose_undoes_relative() -> None:
    origin, pose = Pose2D(1.0, -2.0, 0.7), Pose2D(-0.3, 0.4, -2.9)
    back = compose(origin, relative(origin, pose))
    assert back.distance_to(pose) < 1e-12 and abs(math.remainder(back.theta_rad - pose.theta_rad, 2 * math.pi)) < 1e-12


def test_a_readings_only_map_stays_on_the_lab_and_localization_converges_on_it() -> None:
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        sequencer.activate(TOKEN, "environment_modelling", {"restart": True}, False)
        sequencer.activate(TOKEN, "direct_control", {"linear_mps": 0.0, "angular_radps": 0.8, "duration_s": 8.0},
                           False)
        world.step_for(9.0)
        model = sequencer.perception.environment
        plan = EnvironmentModel()
        plan.add_floor_plan(world.scene)
        from skill_server.skills.scan_matching import distance_field

        off_plan_m = distance_field(plan.occupied(), 3)[model.occupied()] * model.resolution_m
        assert model.occupied().sum() > 300 and np.mean(off_plan_m <= 0.05 + 1e-9) > 0.97
        goal = sequencer.perception.published_map
        assert goal is not None and goal.scans_integrated > 30

        truth = world.snapshot.ground_truth
        sequencer.activate(TOKEN, "localization", {"initial_x_m": truth.x_m + 0.25, "initial_y_m": truth.y_m - 0.25,
                                                   "initial_theta_rad": truth.theta_rad}, False)
        sequencer.activate(TOKEN, "direct_control", {"linear_mps": 0.0, "angular_radps": -0.8, "duration_s": 8.0},
                           True)
        world.step_for(9.0)
        estimate = sequencer.perception.published_estimate
        assert estimate is not None and estimate.converged
        assert world.snapshot.ground_truth.distance_to(estimate.pose) < 0.05
        # The reported spread includes the map-mismatch term, and says which odometry the pose was moved on to.
        assert math.hypot(estimate.std_x_m, estimate.std_y_m) >= estimate.particle_std_m
        assert estimate.odometry is not None and estimate.residual_rms_m > 0
