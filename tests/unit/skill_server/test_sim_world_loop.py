"""The world's own thread: real-time pacing, commands through the queue, reset and clean stop."""

from __future__ import annotations

import threading
import time

import pytest
from skill_sim_helpers import TOKEN

from skill_server.errors import WorldStopped
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World


def test_reset_puts_the_robot_back_and_replays_the_same_trajectory() -> None:
    with World("empty", realtime=False, deadman_timeout_s=100.0) as world:
        world.set_controller(TOKEN)
        world.drive(TOKEN, 1, 0.4, 0.5)
        first = world.step_for(2.0)
        world.reset(seed=0)
        assert world.snapshot.sim_time_s == 0.0 and world.snapshot.ground_truth == Pose2D(0.0, 0.0, 0.0)
        world.drive(TOKEN, 2, 0.4, 0.5)
        again = world.step_for(2.0)
    assert (again.ground_truth, again.odometry) == (first.ground_truth, first.odometry)


def test_a_real_time_loop_keeps_sim_time_with_the_wall_clock() -> None:
    with World("empty", realtime=True) as world:
        world.start()
        first = world.wait_for_snapshot(0, timeout_s=2.0)
        assert first is not None
        time.sleep(0.5)
        elapsed_sim_s = world.snapshot.sim_time_s - first.sim_time_s
    assert elapsed_sim_s == pytest.approx(0.5, abs=0.15)


def test_commands_from_other_threads_run_in_the_loop() -> None:
    with World("empty", realtime=False) as world:
        world.start()
        world.set_pose(Pose2D(1.0, 2.0, 0.5))
        snapshot = world.wait_for_snapshot(world.snapshot.tick, timeout_s=2.0)
        assert snapshot is not None
        assert snapshot.ground_truth.x_m == pytest.approx(1.0, abs=0.01)
        assert snapshot.odometry.pose.y_m == pytest.approx(2.0, abs=0.01)
        with pytest.raises(RuntimeError):
            world.step_for(0.1)


def test_stopping_wakes_waiting_readers_and_refuses_later_commands() -> None:
    world = World("empty", realtime=True)
    world.start()
    world.stop()
    assert not world.is_running
    assert world.wait_for_snapshot(world.snapshot.tick, timeout_s=5.0) is None
    with pytest.raises(WorldStopped):
        world.reset(seed=1)


def _wait_with_a_drive_arriving(duration_s: float, tick_on_drive: bool) -> float:
    """How long the world waits for its next tick (duration_s) when a drive arrives after 50 ms."""
    with World("empty", realtime=False) as world:
        world.set_controller(TOKEN)
        timer = threading.Timer(0.05, lambda: world.drive(TOKEN, 1, 0.2, 0.0))
        timer.start()
        began = time.monotonic()
        world._serve_commands_for(duration_s, tick_on_drive=tick_on_drive)
        timer.join()
        return time.monotonic() - began


def test_a_new_drive_target_ends_the_wait_for_the_next_tick() -> None:
    """Control runs at 40 Hz: a drive arriving mid-period is not left waiting up to 25 ms for its tick."""
    assert _wait_with_a_drive_arriving(5.0, tick_on_drive=True) < 2.0


def test_without_tick_on_drive_the_wait_lasts_its_whole_duration() -> None:
    """Right after an early tick the loop is a tick ahead of the wall clock: it must not run further ahead."""
    assert _wait_with_a_drive_arriving(0.4, tick_on_drive=False) >= 0.4
