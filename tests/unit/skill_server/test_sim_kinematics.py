"""The base moves as a differential drive with ramped accelerations, in sim time."""

from __future__ import annotations

import math

import pytest
from skill_sim_helpers import TOKEN

from skill_server.sim.geometry import wrap_angle
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.world import World


def ramped_distance(speed: float, duration_s: float, accel: float) -> float:
    """Distance covered from rest when the speed ramps up at accel, then holds."""
    ramp_s = speed / accel
    return speed * duration_s - speed * ramp_s / 2.0


@pytest.mark.parametrize("speed_mps", [0.2, 0.5, -0.3])
def test_driving_straight_covers_speed_times_time(empty_world: World, speed_mps: float) -> None:
    empty_world.drive(TOKEN, 1, speed_mps, 0.0)
    snapshot = empty_world.step_for(3.0)
    expected_m = ramped_distance(abs(speed_mps), 3.0, TELEBOT.max_linear_accel_mps2)
    assert math.copysign(1.0, speed_mps) * snapshot.ground_truth.x_m == pytest.approx(expected_m, abs=0.03)
    assert snapshot.ground_truth.y_m == pytest.approx(0.0, abs=0.01)
    assert snapshot.ground_truth.theta_rad == pytest.approx(0.0, abs=0.01)


@pytest.mark.parametrize("turn_radps", [1.0, -1.5])
def test_spinning_turns_rate_times_time_in_place(empty_world: World, turn_radps: float) -> None:
    empty_world.drive(TOKEN, 1, 0.0, turn_radps)
    snapshot = empty_world.step_for(1.5)
    expected_rad = ramped_distance(abs(turn_radps), 1.5, TELEBOT.max_angular_accel_radps2)
    turned_rad = math.copysign(1.0, turn_radps) * wrap_angle(snapshot.ground_truth.theta_rad)
    assert turned_rad == pytest.approx(expected_rad, rel=0.05)
    assert math.hypot(snapshot.ground_truth.x_m, snapshot.ground_truth.y_m) < 0.02


def test_speed_ramps_up_no_faster_than_the_acceleration_limit(empty_world: World) -> None:
    empty_world.drive(TOKEN, 1, 0.5, 0.0)
    snapshot = empty_world.step_for(0.2)
    assert snapshot.commanded_linear_mps == pytest.approx(TELEBOT.max_linear_accel_mps2 * 0.2, abs=0.02)
    assert empty_world.step_for(1.0).commanded_linear_mps == pytest.approx(0.5)


def test_sim_time_advances_by_the_stepped_duration(empty_world: World) -> None:
    before = empty_world.snapshot
    after = empty_world.step_for(1.0)
    assert after.sim_time_s - before.sim_time_s == pytest.approx(1.0, abs=empty_world.tick_dt_s)
    assert after.tick > before.tick
