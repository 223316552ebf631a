"""Sonar cones and the laser measure what the geometry says they should."""

from __future__ import annotations

import math

import pytest
from skill_sim_helpers import WALL_FACE_X_M

from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World


def test_the_robot_carries_sixteen_sonars_and_a_181_beam_front_laser(wall_world: World) -> None:
    info = wall_world.describe()
    assert len(info.sonars) == 16 and len(wall_world.snapshot.sonar_ranges_m) == 16
    assert info.sonars[0].mount_angle_rad == 0.0
    assert info.sonars[4].mount_angle_rad == pytest.approx(math.pi / 2)
    assert info.laser.beam_count == 181 and len(wall_world.snapshot.laser_ranges_m) == 181
    assert (info.laser.angle_min_rad, info.laser.angle_max_rad) == (-math.pi / 2, math.pi / 2)
    assert info.laser.max_range_m == 8.0


@pytest.mark.parametrize("robot_x_m", [0.0, 0.7, 1.4])
def test_laser_centre_beam_and_front_sonar_measure_the_wall_distance(wall_world: World, robot_x_m: float) -> None:
    wall_world.set_pose(Pose2D(robot_x_m, 0.0, 0.0))
    snapshot = wall_world.snapshot
    centre_to_wall_m = WALL_FACE_X_M - robot_x_m
    # The laser sits on the robot's centre; each sonar sits on the body's rim.
    assert snapshot.laser_ranges_m[90] == pytest.approx(centre_to_wall_m, abs=0.03)
    assert snapshot.sonar_ranges_m[0] == pytest.approx(centre_to_wall_m - wall_world.spec.body_radius_m, abs=0.08)


def test_sensors_report_max_range_where_nothing_echoes(wall_world: World) -> None:
    snapshot = wall_world.snapshot
    rear_sonar = 8
    assert snapshot.sonar_ranges_m[rear_sonar] == wall_world.describe().sonars[rear_sonar].max_range_m
    assert snapshot.laser_ranges_m[0] == pytest.approx(8.0)  # straight right, along the 10 m floor


def test_laser_beams_sweep_right_to_left(wall_world: World) -> None:
    wall_world.set_pose(Pose2D(1.0, 0.0, math.pi / 2))  # the wall is now on the robot's right
    ranges = wall_world.snapshot.laser_ranges_m
    assert ranges[0] == pytest.approx(WALL_FACE_X_M - 1.0, abs=0.03)
    assert ranges[180] == pytest.approx(8.0)


def test_a_sonar_cone_sees_an_obstacle_beside_its_axis_that_one_ray_misses(pole_world: World) -> None:
    sonar = pole_world._sonar
    pose = pole_world.snapshot.ground_truth
    axis_from, axis_to = sonar.rays(pose, single_ray=True)
    single_ray_ranges = sonar.ranges(pole_world.cast_rays(axis_from, axis_to), None, single_ray=True)
    assert single_ray_ranges[0] == sonar.spec.max_range_m
    assert pole_world.snapshot.sonar_ranges_m[0] == pytest.approx(1.5, abs=0.08)


def test_range_sensors_do_not_see_the_robot_itself(wall_world: World) -> None:
    wall_world.set_pose(Pose2D(-2.0, 0.0, 0.0))
    snapshot = wall_world.snapshot
    assert min(snapshot.laser_ranges_m) > wall_world.spec.body_radius_m
    assert min(snapshot.sonar_ranges_m) > 0.5
