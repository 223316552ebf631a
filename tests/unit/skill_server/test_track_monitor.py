"""Track runs: arrival at A and B, border-line contact (an error that restarts the run), and run times."""

from __future__ import annotations

import time

import pytest

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import get_scene, known_scenes
from skill_server.sim.track_monitor import BorderLine, TrackMonitor, TrackSpec, segment_distance_m, touches_line


def drive(monitor: TrackMonitor, points: list[tuple[float, float]], start_s: float, step_s: float = 0.5) -> float:
    """Feeds poses one step apart; returns the time after the last."""
    t = start_s
    for x, y in points:
        monitor.observe(Pose2D(x, y, 0.0), t)
        t += step_s
    return t


def kinds(monitor: TrackMonitor) -> list[str]:
    return [event.kind for event in monitor.events_after(0, 0)]


def test_track_a_times_the_round_trip_from_leaving_a_to_coming_back() -> None:
    monitor = TrackMonitor(get_scene("course-A").track)
    drive(monitor, [(-2.5, 0.0), (-2.4, 0.0)], 0.0)  # still within A: nothing starts
    assert kinds(monitor) == [] and monitor.state().started_unix_s == 0.0
    before = time.time()
    t = drive(monitor, [(-2.0, 0.0), (0.0, 0.0), (2.4, 0.0), (0.0, 0.0), (-2.45, 0.0)], 10.0, 2.0)
    assert kinds(monitor) == ["started", "reached_b", "reached_a", "finished"]
    state = monitor.state()
    assert state.phase == "finished" and state.last_attempt == 1
    assert state.last_total_time_s == pytest.approx(8.0) and state.last_errors == 0
    # The wall clock at the start of each attempt tells a trial which runs began within it.
    assert before <= state.last_started_unix_s == state.started_unix_s <= state.last_finished_unix_s
    # Leaving A again starts attempt 2.
    time.sleep(0.01)
    drive(monitor, [(-2.5, 0.0), (-1.5, 0.0)], t)
    later = monitor.state()
    assert later.attempt == 2 and later.phase == "to_b"
    assert later.started_unix_s > later.last_started_unix_s == state.last_started_unix_s


def test_track_b_is_one_way_and_a_line_contact_restarts_the_run_counting_an_error() -> None:
    track = get_scene("course-B").track
    monitor = TrackMonitor(track)
    drive(monitor, [(-3.0, -1.5), (-2.0, -1.5)], 0.0)
    # Drifting south onto the border line y = -2.1: the body (0.2 m) touches it at y < -1.875.
    assert monitor.observe(Pose2D(-1.0, -1.9, 0.0), 1.0) is True
    assert kinds(monitor)[-1] == "line_contact" and monitor.state().errors == 1
    assert monitor.state().phase == "at_start"
    # The world puts the robot back at A; the same attempt goes on and its clock keeps running.
    t = drive(monitor, [(-3.0, -1.5), (-2.0, -1.5), (0.0, -1.5), (0.0, 0.0), (0.0, 1.5), (2.0, 1.5), (3.0, 1.5)],
              2.0, 1.0)
    state = monitor.state()
    assert kinds(monitor)[-2:] == ["reached_b", "finished"]
    assert state.last_attempt == 1 and state.last_errors == 1
    assert state.last_total_time_s == pytest.approx(t - 1.0 - 0.5 * 1 - 1.0, abs=1.5)


def test_a_restart_gives_up_the_attempt_mid_course_and_the_next_departure_from_a_is_timed_from_zero() -> None:
    monitor = TrackMonitor(get_scene("course-A").track)
    drive(monitor, [(-2.5, 0.0), (-2.0, 0.0), (0.0, 0.0)], 0.0, 5.0)
    assert monitor.state().attempt == 1 and monitor.state().phase == "to_b"
    assert monitor.restart(12.0) is True
    given_up = monitor.state()
    assert kinds(monitor)[-1] == "restarted" and given_up.phase == "finished"
    assert (given_up.attempt, given_up.elapsed_s, given_up.errors, given_up.last_attempt) == (0, 0.0, 0, 0)
    # Driving on from mid-course starts nothing; the run begins when the robot leaves A again.
    drive(monitor, [(1.0, 0.0), (2.4, 0.0)], 20.0)
    assert monitor.state().phase == "finished" and kinds(monitor)[-1] == "restarted"
    before = time.time()
    t = drive(monitor, [(0.0, 0.0), (-2.45, 0.0), (-2.0, 0.0), (2.4, 0.0), (-2.45, 0.0)], 30.0, 2.0)
    state = monitor.state()
    assert kinds(monitor)[-4:] == ["started", "reached_b", "reached_a", "finished"]
    assert state.last_attempt == 1 and state.last_total_time_s == pytest.approx(t - 2.0 - 34.0)
    assert state.last_started_unix_s >= before


def test_a_restart_after_a_line_contact_ends_the_attempt_the_robot_was_sent_back_in() -> None:
    monitor = TrackMonitor(get_scene("course-B").track)
    drive(monitor, [(-3.0, -1.5), (-2.0, -1.5)], 0.0)
    assert monitor.observe(Pose2D(-1.0, -1.9, 0.0), 1.0) is True  # back at A, the attempt's clock running
    assert monitor.restart(2.0) is True and monitor.state().errors == 0
    drive(monitor, [(-3.0, -1.5), (-2.0, -1.5), (-1.5, -1.5)], 10.0)
    state = monitor.state()
    assert (state.phase, state.attempt, state.errors) == ("to_b", 1, 0) and state.elapsed_s == pytest.approx(0.5)
    assert state.started_unix_s > 0


def test_a_restart_with_no_attempt_under_way_changes_nothing() -> None:
    monitor = TrackMonitor(get_scene("course-A").track)
    assert monitor.restart(0.0) is False
    drive(monitor, [(-2.5, 0.0), (-2.0, 0.0), (2.4, 0.0), (-2.45, 0.0)], 0.0)
    finished = monitor.state()
    assert monitor.restart(5.0) is False and monitor.state() == finished and "restarted" not in kinds(monitor)


def test_the_winding_centre_line_of_track_b_touches_no_border() -> None:
    track = get_scene("course-B").track
    centre = [(-3 + i * 0.1, -1.5) for i in range(31)] + [(0.0, -1.5 + i * 0.1) for i in range(31)]
    centre += [(i * 0.1, 1.5) for i in range(31)]
    assert all(touches_line(Pose2D(x, y), track) is None for x, y in centre)


@pytest.mark.parametrize(("point", "expected"), [((0.0, 1.0), 1.0), ((-1.0, 0.0), 1.0), ((3.0, 0.0), 1.0),
                                                 ((1.0, 0.0), 0.0)])
def test_segment_distance(point: tuple[float, float], expected: float) -> None:
    assert segment_distance_m(*point, BorderLine(0.0, 0.0, 2.0, 0.0)) == pytest.approx(expected)


def test_track_scenes_are_registered_and_plain_scenes_have_no_track() -> None:
    assert {"course-A", "course-B"} <= set(known_scenes())
    assert get_scene("lab").track is None
    a = get_scene("course-A")
    assert a.track.round_trip and a.track.lines == ()
    assert (a.spawn.x_m, a.spawn.y_m) == (a.track.a_x_m, a.track.a_y_m)
    assert isinstance(TrackSpec, type)


def test_the_world_puts_the_robot_back_at_a_after_a_line_contact() -> None:
    from skill_server.sim.world import World

    with World("course-B", realtime=False) as world:
        world.set_pose(Pose2D(-2.0, -1.5, 0.0))
        world.step_for(0.1)
        assert world.track_monitor.state().phase == "to_b"
        world.set_pose(Pose2D(-1.0, -1.95, 0.0))
        snapshot = world.step_for(0.1)
        assert snapshot.ground_truth.distance_to(Pose2D(-3.0, -1.5)) < 0.05
        assert world.track_monitor.state().errors == 1
