"""The line of tape and the line sensor: the sensor reads the tape where the world paints it, the grader measures
the same line, and the student's API places the cells where the robot has them."""

from __future__ import annotations

import numpy as np

from middleware.exercises.catalogue import LAB_LINE_RUBRIC
from middleware.exercises.grading import line_distance, line_points
from skill_server.sim.floor_line import LineSensor, distances_to_line, paint_patches
from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import LAB_LINE, get_scene
from tests.integration.exercises.world_backend import load_api


def test_the_lab_has_the_line_the_catalogue_grades() -> None:
    line = get_scene("lab").line
    assert line == LAB_LINE
    assert {k: getattr(line, k) for k in LAB_LINE_RUBRIC} == LAB_LINE_RUBRIC
    assert get_scene("empty").line is None


def test_the_grader_and_the_sensor_measure_the_same_distance() -> None:
    points = np.random.default_rng(3).uniform(-2.5, 2.0, (300, 2))
    sensor = distances_to_line(LAB_LINE, points)
    grader = [line_distance(x, y, LAB_LINE_RUBRIC) for x, y in points]
    assert np.allclose(sensor, grader)
    assert max(line_distance(x, y, LAB_LINE_RUBRIC) for x, y in line_points(LAB_LINE_RUBRIC)) < 1e-9
    assert abs(len(line_points(LAB_LINE_RUBRIC)) * 0.05 - LAB_LINE.length_m) < 0.1  # a point every 5 cm


def test_the_painted_tape_covers_the_line_the_sensor_reads() -> None:
    patches = paint_patches(LAB_LINE)
    for x, y in LAB_LINE.centre_points(0.02):
        assert any(abs(x - cx) <= hx + 1e-9 and abs(y - cy) <= hy + 1e-9 for cx, cy, hx, hy in patches), (x, y)


def test_a_cell_over_the_tape_reads_one_and_over_bare_floor_zero() -> None:
    sensor = LineSensor(LAB_LINE)
    on_line = Pose2D(-0.5 - sensor.spec.ahead_m, LAB_LINE.y_min_m, 0.0)  # the middle cell over the bottom run
    values = sensor.read(on_line, None)
    assert values[2] == 1.0 and values[0] == values[4] == 0.0
    shifted = Pose2D(on_line.x_m, on_line.y_m - 0.045, 0.0)  # the left cell over it now
    assert sensor.read(shifted, None)[0] == 1.0
    assert sensor.read(Pose2D(0.0, 0.0, 0.0), None) == (0.0,) * 5
    noisy = sensor.read(on_line, np.random.default_rng(1))
    assert all(0.0 <= v <= 1.0 for v in noisy) and noisy != values
    assert LineSensor(None).read(on_line, None) == ()


def test_the_api_places_the_cells_where_the_robot_has_them() -> None:
    api = load_api()
    assert LAB_LINE.sensor.offsets_m == api.LINE_OFFSETS_M
    assert LAB_LINE.sensor.ahead_m == api.LINE_AHEAD_M
