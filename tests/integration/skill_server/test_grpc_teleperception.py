"""Teleperception over real gRPC: the evidence grid accumulates sonar and laser readings at the odometry pose while
someone watches, static and moving apart, resets under the supervisory rule, and keeps the raw readings."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import grpc
import numpy as np
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer

DEADLINE_S = 30.0
TOKEN = "perception-token"
EAST_WALL_X_M = 4.0  # the lab's east wall's inner face, straight ahead of the spawn at (0, 0) facing +x


@pytest.fixture
def robot(fresh_server: SkillServer) -> Iterator[robot_pb2_grpc.RobotStub]:
    """A stub on a fresh fast-mode lab robot nobody controls yet."""
    channel = grpc.insecure_channel(fresh_server.address)
    yield robot_pb2_grpc.RobotStub(channel)
    channel.close()


def evidence(robot: robot_pb2_grpc.RobotStub, sensor: int = 0, part: int = 0,
             watch: bool = True) -> robot_pb2.EvidenceGrid:
    """GetEvidenceGrid for the chosen layers."""
    return robot.GetEvidenceGrid(robot_pb2.GetEvidenceGridRequest(watch=watch, sensor=sensor, part=part),
                                 timeout=DEADLINE_S)


def wait_for(robot: robot_pb2_grpc.RobotStub, done: Callable[[robot_pb2.EvidenceGrid], bool],
             within_s: float = 20.0) -> robot_pb2.EvidenceGrid:
    """Reads (and so watches) the grid until done says so."""
    ends = time.monotonic() + within_s
    while True:
        answer = evidence(robot)
        if done(answer) or time.monotonic() > ends:
            return answer
        time.sleep(0.05)


def cells(answer: robot_pb2.EvidenceGrid) -> np.ndarray:
    """The grid as an array indexed [iy, ix] (percent occupancy, 255 unknown)."""
    grid = answer.grid
    return np.frombuffer(grid.cells, dtype=np.uint8).reshape(grid.height_cells, grid.width_cells)


def cell_at(answer: robot_pb2.EvidenceGrid, x_m: float, y_m: float) -> int:
    """The value of the cell holding (x_m, y_m)."""
    grid = answer.grid
    ix = math.floor((x_m - grid.origin_x_m) / grid.resolution_m)
    iy = math.floor((y_m - grid.origin_y_m) / grid.resolution_m)
    return int(cells(answer)[iy, ix])


def known(answer: robot_pb2.EvidenceGrid) -> int:
    """How many cells some reading touched."""
    return int(np.count_nonzero(cells(answer) != 255))


def test_nothing_accumulates_until_someone_watches(robot: robot_pb2_grpc.RobotStub) -> None:
    time.sleep(0.5)
    unwatched = evidence(robot, watch=False)
    assert not unwatched.accumulating
    assert unwatched.sonar_scans == unwatched.laser_scans == 0
    assert known(unwatched) == 0


def test_standing_readings_free_the_space_ahead_and_mark_the_wall_it_faces(robot: robot_pb2_grpc.RobotStub) -> None:
    stood = wait_for(robot, lambda a: a.static_scans >= 20)
    assert stood.accumulating and stood.moving_scans == 0
    assert stood.sonar_scans == stood.laser_scans == stood.static_scans >= 20
    for sensor in (robot_pb2.EVIDENCE_SENSOR_SONAR, robot_pb2.EVIDENCE_SENSOR_LASER):
        layer = evidence(robot, sensor=sensor, part=robot_pb2.EVIDENCE_PART_STATIC)
        for x_m in (0.8, 1.5, 2.5, 3.5):
            assert cell_at(layer, x_m, 0.0) < 30, f"sensor {sensor}: free space ahead at x={x_m}"
        assert cell_at(layer, EAST_WALL_X_M + 0.03, 0.0) > 70, f"sensor {sensor}: the wall it faces"
        assert cell_at(layer, -3.5, 0.0) == 255 or sensor == robot_pb2.EVIDENCE_SENSOR_SONAR, \
            "the laser sweeps only the half-plane ahead"
    moving = evidence(robot, part=robot_pb2.EVIDENCE_PART_MOVING)
    assert known(moving) == 0, "nothing was read while driving"
    assert math.hypot(stood.odometry.x_m, stood.odometry.y_m) < 1e-3, "the robot stood at its dock"


def test_driving_adds_moving_readings_that_know_more_cells(robot: robot_pb2_grpc.RobotStub) -> None:
    stood = wait_for(robot, lambda a: a.static_scans >= 10)
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    robot.ActivateSkill(robot_pb2.ActivateSkillRequest(token=TOKEN, skill="direct_control", parameters={
        "linear_mps": robot_pb2.ParameterValue(double_value=0.25),
        "angular_radps": robot_pb2.ParameterValue(double_value=0.8),
        "duration_s": robot_pb2.ParameterValue(double_value=6.0)}), timeout=DEADLINE_S)
    driven = wait_for(robot, lambda a: a.moving_scans >= 40)
    assert driven.moving_scans >= 40
    assert known(driven) > known(stood) * 1.3, "turning shows the laser the room behind the robot"
    moving = evidence(robot, part=robot_pb2.EVIDENCE_PART_MOVING)
    assert known(moving) > 0
    assert math.hypot(driven.odometry.x_m, driven.odometry.y_m) > 0.05


def test_a_reset_is_supervisory_and_forgets_grid_counts_and_readings(robot: robot_pb2_grpc.RobotStub) -> None:
    wait_for(robot, lambda a: a.static_scans >= 5)
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    with pytest.raises(grpc.RpcError) as refused:
        robot.ResetEvidenceGrid(robot_pb2.ResetEvidenceGridRequest(token="someone-else"), timeout=DEADLINE_S)
    assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED
    assert evidence(robot).static_scans >= 5, "a refused reset changes nothing"
    reset = robot.ResetEvidenceGrid(robot_pb2.ResetEvidenceGridRequest(token=TOKEN), timeout=DEADLINE_S)
    assert reset.sonar_scans <= 1 and reset.static_scans <= 1  # one reading may land between reset and answer
    readings = robot.GetPerceptionReadings(robot_pb2.GetPerceptionReadingsRequest(), timeout=DEADLINE_S)
    assert len(readings.scans) <= 2  # and one more may land between the answer and this read (10 a second)


def test_the_raw_readings_carry_pose_part_and_both_sensors_numbered_for_paging(
        robot: robot_pb2_grpc.RobotStub) -> None:
    wait_for(robot, lambda a: a.static_scans >= 6)
    info = robot.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=DEADLINE_S)
    readings = robot.GetPerceptionReadings(robot_pb2.GetPerceptionReadingsRequest(), timeout=DEADLINE_S).scans
    assert len(readings) >= 6
    first = readings[0]
    assert len(first.sonar_ranges_m) == len(info.sonars)
    assert len(first.laser_ranges_m) == info.laser.beam_count
    assert first.part == robot_pb2.EVIDENCE_PART_STATIC and first.capture_unix_s > 0
    assert abs(first.laser_ranges_m[info.laser.beam_count // 2] - EAST_WALL_X_M) < 0.05
    assert [s.index for s in readings] == sorted(s.index for s in readings)
    later = robot.GetPerceptionReadings(robot_pb2.GetPerceptionReadingsRequest(after_index=readings[2].index),
                                        timeout=DEADLINE_S).scans
    assert later[0].index == readings[3].index


def test_an_unknown_layer_is_invalid_argument_naming_the_field(robot: robot_pb2_grpc.RobotStub) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        robot.GetEvidenceGrid(robot_pb2.GetEvidenceGridRequest(sensor=7), timeout=DEADLINE_S)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "sensor" in refused.value.details()
