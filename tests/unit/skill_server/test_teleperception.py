"""Teleperception's evidence grid and accumulator without a server: readings placed at the odometry pose, per sensor
and part, only while watched, at most 10 per second of sim time, and a reset that forgets everything."""

from __future__ import annotations

import math

import numpy as np

from skill_server.sim.battery import FULL_BATTERY
from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.odometry import OdometryReading
from skill_server.sim.snapshots import RobotSnapshot
from skill_server.sim.sonar import SonarRingSpec
from skill_server.skills.evidence_grid import EvidenceGrid, RangeSensors
from skill_server.skills.teleperception import WATCH_S, Teleperception

SONAR = SonarRingSpec(count=4, mount_radius_m=0.2)
LASER = LaserSpec(beam_count=5)


def grid() -> EvidenceGrid:
    return EvidenceGrid(4.0, 3.0, RangeSensors(SONAR.geometries(), SONAR.mount_radius_m, LASER))


def value_at(view, x_m: float, y_m: float) -> int:
    cells = np.frombuffer(view.cells, dtype=np.uint8).reshape(view.height_cells, view.width_cells)
    ix = math.floor((x_m - view.origin_x_m) / view.resolution_m)
    iy = math.floor((y_m - view.origin_y_m) / view.resolution_m)
    return int(cells[iy, ix])


def snapshot(sim_time_s: float, pose: Pose2D, linear_mps: float = 0.0, laser: tuple[float, ...] | None = None,
             truth: Pose2D | None = None) -> RobotSnapshot:
    return RobotSnapshot(
        tick=int(sim_time_s * 60), sim_time_s=sim_time_s, capture_unix_s=1000.0 + sim_time_s, last_applied_sequence=0,
        odometry=OdometryReading(pose, linear_mps, 0.0), ground_truth=truth or pose,
        sonar_ranges_m=(2.0, 5.0, 5.0, 5.0), laser_ranges_m=laser or (8.0, 8.0, 2.05, 8.0, 8.0),
        deadman_stopped=False, commanded_linear_mps=linear_mps, commanded_angular_radps=0.0, battery=FULL_BATTERY)


def test_a_sonar_echo_frees_its_cone_and_marks_its_arc() -> None:
    evidence = grid()
    evidence.add_sonar(Pose2D(0.0, 0.0, 0.0), (2.0, 5.0, 5.0, 5.0), "static")
    view = evidence.view(("sonar",), ("static",))
    assert value_at(view, 1.0, 0.0) < 50 and value_at(view, 2.2, 0.0) > 50  # echo at 0.2 m rim + 2.0 m
    assert value_at(view, 2.15, 0.4) > 50, "the arc spans the cone, not just its axis"
    assert value_at(view, 0.0, -2.0) < 50, "a sonar without echo still frees space ahead of it"
    assert value_at(evidence.view(("laser",)), 1.0, 0.0) == 255, "the laser layer is untouched"


def test_readings_are_placed_at_the_odometry_pose_not_the_truth() -> None:
    perception = Teleperception(grid(), clock=lambda: 0.0)
    perception.watch()
    perception.observe(snapshot(0.0, Pose2D(1.0, 0.0, 0.0), truth=Pose2D(-1.0, 0.0, 0.0)))
    view = perception.state(("laser",)).view
    assert value_at(view, 3.05, 0.0) > 50 and value_at(view, 1.05, 0.0) < 50


def test_it_integrates_only_while_watched_and_files_each_reading_under_its_part() -> None:
    now = [0.0]
    perception = Teleperception(grid(), clock=lambda: now[0])
    perception.observe(snapshot(0.0, Pose2D()))
    assert perception.state().scans_by_part == {"static": 0, "moving": 0}, "nobody watches yet"
    perception.watch()
    perception.observe(snapshot(0.1, Pose2D()))
    perception.observe(snapshot(0.15, Pose2D(), laser=(8.0, 8.0, 2.1, 8.0, 8.0)))  # under 0.1 s: skipped
    perception.observe(snapshot(0.2, Pose2D(), linear_mps=0.2, laser=(8.0, 8.0, 1.9, 8.0, 8.0)))
    state = perception.state()
    assert state.scans_by_part == {"static": 1, "moving": 1} and state.scans_by_sensor == {"sonar": 2, "laser": 2}
    assert [s.part for s in perception.scans_after(0)] == ["static", "moving"]
    now[0] = WATCH_S + 1
    perception.observe(snapshot(0.5, Pose2D(), laser=(8.0, 8.0, 1.8, 8.0, 8.0)))
    assert not perception.state().accumulating and perception.state().scans_by_part["moving"] == 1


def test_a_reset_forgets_grid_counts_and_readings_but_numbering_goes_on() -> None:
    perception = Teleperception(grid(), clock=lambda: 0.0)
    perception.watch()
    perception.observe(snapshot(0.0, Pose2D()))
    perception.reset()
    state = perception.state()
    assert state.scans_by_sensor == {"sonar": 0, "laser": 0} and perception.scans_after(0) == []
    assert set(state.view.cells) == {255}
    perception.observe(snapshot(0.2, Pose2D(), laser=(8.0, 8.0, 2.2, 8.0, 8.0)))
    assert [s.index for s in perception.scans_after(0)] == [2]


def test_the_readings_are_answered_in_pages_of_at_most_the_limit() -> None:
    perception = Teleperception(grid(), clock=lambda: 0.0)
    perception.watch()
    for step in range(7):
        perception.observe(snapshot(0.2 * step, Pose2D(), laser=(8.0, 8.0, 2.0 + 0.01 * step, 8.0, 8.0)))
    first = perception.scans_after(0, limit=3)
    assert [s.index for s in first] == [1, 2, 3]
    assert [s.index for s in perception.scans_after(first[-1].index, limit=3)] == [4, 5, 6]
    assert [s.index for s in perception.scans_after(6, limit=3)] == [7]
