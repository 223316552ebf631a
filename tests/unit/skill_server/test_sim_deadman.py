"""The deadman stops the base when direct commands stop arriving, in sim time."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from skill_sim_helpers import TOKEN

from skill_server.sim.world import World

DEADMAN_S = 0.4


@pytest.fixture
def world() -> Iterator[World]:
    with World("empty", realtime=False, deadman_timeout_s=DEADMAN_S) as world:
        world.set_controller(TOKEN)
        yield world


def test_base_stops_and_says_so_when_commands_stop(world: World) -> None:
    world.drive(TOKEN, 1, 0.3, 0.0)
    moving = world.step_for(DEADMAN_S - 0.1)
    assert not moving.deadman_stopped and moving.commanded_linear_mps > 0.2
    fired = world.step_for(0.2)
    assert fired.deadman_stopped
    stopped = world.step_for(0.6)
    assert stopped.commanded_linear_mps == 0.0 and abs(stopped.odometry.linear_mps) < 0.02
    later = world.step_for(0.5)
    assert later.ground_truth.x_m == pytest.approx(stopped.ground_truth.x_m, abs=0.005)
    assert later.deadman_stopped


def test_commands_arriving_in_time_keep_the_base_moving(world: World) -> None:
    for sequence in range(1, 8):
        world.drive(TOKEN, sequence, 0.3, 0.0)
        snapshot = world.step_for(DEADMAN_S / 2)
    assert not snapshot.deadman_stopped and snapshot.commanded_linear_mps == pytest.approx(0.3)


def test_a_new_command_after_the_deadman_clears_the_flag(world: World) -> None:
    world.drive(TOKEN, 1, 0.3, 0.0)
    assert world.step_for(1.0).deadman_stopped
    world.drive(TOKEN, 2, 0.3, 0.0)
    snapshot = world.step_for(0.1)
    assert not snapshot.deadman_stopped and snapshot.commanded_linear_mps > 0


def test_acks_after_the_deadman_report_the_base_stopped(world: World) -> None:
    world.drive(TOKEN, 5, 0.3, 0.0)
    world.step_for(1.0)
    ack = world.drive(TOKEN, 4, 0.3, 0.0)  # older: ignored
    assert (ack.applied_sequence, ack.linear_mps) == (5, 0.0)


def test_an_idle_robot_is_not_reported_as_deadman_stopped(world: World) -> None:
    assert not world.step_for(1.0).deadman_stopped


def test_deadman_timeout_must_be_positive_and_finite() -> None:
    from skill_server.errors import InvalidParameter

    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(InvalidParameter, match="deadman_timeout_s"):
            World("empty", realtime=False, deadman_timeout_s=bad)


def test_a_stop_command_is_not_reported_as_deadman_stopped(world: World) -> None:
    world.drive(TOKEN, 1, 0.3, 0.0)
    world.step_for(0.2)
    world.drive(TOKEN, 2, 0.0, 0.0)  # the pad's stop on a normal key release
    snapshot = world.step_for(1.5)
    assert not snapshot.deadman_stopped and snapshot.commanded_linear_mps == 0.0
