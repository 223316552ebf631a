"""Odometry drifts from ground truth by a small, seed-reproducible amount."""

from __future__ import annotations

import math

from skill_sim_helpers import TOKEN

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
