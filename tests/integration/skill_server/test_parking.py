"""A real-time robot nobody commands parks (no physics steps, sensors still published, sim time following the wall
clock; a camera viewer gets the frame rendered once, again at its rate) and wakes at once for a drive, a skill or
any command its loop runs (a robot placed elsewhere is stepped again)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest

from skill_server.server import SkillServer, create_server
from skill_server.sim.world import PARK_AFTER_S, PARKED_PERIOD_S

TOKEN = "owner"


@pytest.fixture
def server() -> Iterator[SkillServer]:
    running = create_server(port=0, scene="lab", controller_token=TOKEN)
    yield running
    running.stop()


def _within(seconds: float, condition: Callable[[], bool]) -> float:
    started = time.monotonic()
    while time.monotonic() - started < seconds:
        if condition():
            return time.monotonic() - started
        time.sleep(0.001)
    pytest.fail(f"not within {seconds} s")


def test_an_idle_robot_parks_and_keeps_publishing_with_sim_time_following_the_wall(server: SkillServer) -> None:
    world = server.world
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    before, wall_before = world.snapshot, time.monotonic()
    time.sleep(1.5)
    after, wall_after = world.snapshot, time.monotonic()
    assert world.parked and after.tick > before.tick
    assert abs((after.sim_time_s - before.sim_time_s) - (wall_after - wall_before)) < 0.4
    assert after.odometry.pose == before.odometry.pose  # nothing moved
    assert after.laser_ranges_m != before.laser_ranges_m  # fresh readings (their noise), not a frozen snapshot


def test_a_parked_robot_publishes_at_its_rate_when_each_publication_comes_late(server: SkillServer) -> None:
    """A loaded machine wakes the parked loop late and its publication takes time: each wait used to start after
    that, so 4 Hz became 3.8 Hz on the shared test machine (3.4 Hz here) and a graded run held fewer samples than
    its length promised; the publications keep to their grid, the robot's pose log with them."""
    world = server.world
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    published: list[float] = []
    world.observe_snapshots(lambda snapshot: (published.append(snapshot.capture_unix_s), time.sleep(0.04)))
    _within(2 * PARKED_PERIOD_S, lambda: len(published) >= 1)
    time.sleep(5.0)
    first = published[0]
    within = [at for at in published if at < first + 5.0]
    logged = world.pose_log.between(first, first + 5.0)[0]
    assert world.parked and len(within) >= 5.0 / PARKED_PERIOD_S - 1, len(within)
    assert len(logged) >= 5.0 / PARKED_PERIOD_S - 1, [at for at, *_ in logged]


def test_a_drive_wakes_a_parked_robot_at_once_and_it_parks_again_once_stopped(server: SkillServer) -> None:
    world = server.world
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    start = world.snapshot.odometry.pose
    world.drive(TOKEN, 1, 0.3, 0.0)
    assert _within(0.2, lambda: not world.parked) < 0.2
    _within(0.2, lambda: world.snapshot.odometry.linear_mps > 0.01)
    for sequence in range(2, 6):  # held as the console does, under the deadman
        time.sleep(0.1)
        world.drive(TOKEN, sequence, 0.3, 0.0)
    world.drive(TOKEN, 6, 0.0, 0.0)
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    assert world.snapshot.odometry.pose.x_m - start.x_m > 0.05


def test_a_camera_viewer_of_a_parked_robot_gets_frames_at_its_rate_rendered_once(server: SkillServer) -> None:
    world = server.world
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    rendered = 0
    render = world.render_frame

    def counted() -> object:
        nonlocal rendered
        rendered += 1
        return render()

    world.render_frame = counted  # type: ignore[method-assign]
    subscription = world.subscribe_camera(10)
    time.sleep(0.1)
    first = world.latest_frame
    assert first is not None
    time.sleep(2.0)
    last = world.latest_frame
    assert world.parked and rendered == 1  # the world stands still: one image, sent again
    assert last is not None and last.jpeg == first.jpeg
    assert 15 <= last.frame_sequence - first.frame_sequence <= 21  # 10 a second
    assert 1.5 < last.sim_time_s - first.sim_time_s < 2.5
    subscription.close()


def test_a_placed_robot_is_stepped_again_and_its_camera_renders_the_new_view(server: SkillServer) -> None:
    world = server.world
    subscription = world.subscribe_camera(10)
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    before = world.latest_frame
    start = world.snapshot.ground_truth
    world.set_pose(type(start)(start.x_m + 0.5, start.y_m, start.theta_rad))
    _within(0.2, lambda: not world.parked)
    _within(2.0, lambda: world.latest_frame is not None and world.latest_frame.jpeg != before.jpeg)
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    subscription.close()


def test_a_running_skill_keeps_the_robot_awake(server: SkillServer) -> None:
    world = server.world
    _within(PARK_AFTER_S + 2.0, lambda: world.parked)
    server.robot.activate(TOKEN, "environment_modelling", {}, preempt=False)
    _within(0.2, lambda: not world.parked)
    time.sleep(PARK_AFTER_S + 0.5)
    assert not world.parked  # a perceptive skill runs: the robot stays awake
