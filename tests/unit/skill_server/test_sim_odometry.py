"""Odometry drifts from ground truth by a small, seed-reproducible amount."""

from __future__ import annotations

import math

import numpy as np
import pytest
from skill_sim_helpers import TOKEN

from skill_server.sim.geometry import Pose2D
from skill_server.sim.odometry import OdometryNoise, WheelOdometry
from skill_server.sim.snapshots import RobotSnapshot
from skill_server.sim.world import World


def drive_a_square_ish_loop(seed: int) -> RobotSnapshot:
    """About 4 m of driving with turns, from a fresh world with the given seed."""
    with World("empty", seed=seed, realtime=False, deadman_timeout_s=1000.0) as world:
        world.set_controller(TOKEN)
        sequence = 0
        for _ in range(4):
            sequence += 1
            world.drive(TOKEN, sequence, 0.5, 0.0)
            world.step_for(2.0)
            sequence += 1
            world.drive(TOKEN, sequence, 0.0, 1.0)
            world.step_for(1.2)
        return world.step_for(0.1)


def pose_error_m(snapshot: RobotSnapshot) -> float:
    """Distance between where odometry thinks the robot is and where it is."""
    return snapshot.odometry.pose.distance_to(snapshot.ground_truth)


def test_odometry_drifts_a_little_from_ground_truth() -> None:
    snapshot = drive_a_square_ish_loop(seed=1)
    assert math.hypot(snapshot.ground_truth.x_m, snapshot.ground_truth.y_m) > 0.5
    assert 0.005 < pose_error_m(snapshot) < 0.5


def test_same_seed_gives_the_same_odometry() -> None:
    first, second = drive_a_square_ish_loop(seed=7), drive_a_square_ish_loop(seed=7)
    assert first.odometry == second.odometry
    assert first.ground_truth == second.ground_truth


def test_different_seeds_drift_differently() -> None:
    assert drive_a_square_ish_loop(seed=1).odometry.pose != drive_a_square_ish_loop(seed=2).odometry.pose


def test_odometry_starts_at_the_spawn_pose_and_tracks_speed(empty_world: World) -> None:
    assert empty_world.snapshot.odometry.pose == empty_world.snapshot.ground_truth
    empty_world.drive(TOKEN, 1, 0.4, 0.0)
    snapshot = empty_world.step_for(2.0)
    assert abs(snapshot.odometry.linear_mps - 0.4) < 0.1


def spread_of_distance_m(dt_s: float, seeds: int = 300) -> float:
    """The std over seeds of the distance odometry reports for 1 m of straight driving read every dt_s."""
    spec = World("empty", seed=0, realtime=False).spec
    step_rad = 1.0 / spec.wheel_radius_m * dt_s  # 1 m/s
    noise = OdometryNoise(scale_error_std=0.0)
    finals = []
    for seed in range(seeds):
        odometry = WheelOdometry(spec, Pose2D(0.0, 0.0, 0.0), np.random.default_rng(seed), noise)
        odometry.update(0.0, 0.0, dt_s)
        for index in range(1, round(1.0 / dt_s) + 1):
            reading = odometry.update(index * step_rad, index * step_rad, dt_s)
        finals.append(reading.pose.x_m)
    return float(np.std(finals))


def test_the_drift_over_a_distance_does_not_depend_on_how_often_the_wheels_are_read() -> None:
    every_60th, every_20th = spread_of_distance_m(1.0 / 60.0), spread_of_distance_m(1.0 / 20.0)
    assert every_60th > 0.0005
    assert every_20th == pytest.approx(every_60th, rel=0.2)
