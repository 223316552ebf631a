"""The student's robot API (client_ui/static/pages/exercises/telelab.py) reads the telemetry the page relays to the
worker, built by the middleware's own packing (robots/messages.py), not a test's copy of it: every documented
sensor (odometry, sonar, laser, the virtual bumper, the line sensor, the battery) and the localization estimate the
page adds from the localization channel. A key renamed on either side would leave the API answering its defaults
(a battery always full, no sonar), which no other test reads."""

from __future__ import annotations

import json
import math
from typing import Any

from middleware.robots.messages import pack_localization, pack_telemetry
from protos.telelab.v1 import robot_pb2
from tests.integration.exercises.world_backend import load_api


def relayed(telemetry: robot_pb2.Telemetry, localization: robot_pb2.LocalizationUpdate) -> dict[str, Any]:
    """What the worker reads, as exercise-run.js builds it: the telemetry message without the truth, its
    camera_pose null, and `localization` taken from the localization channel's message (its truthless version)."""
    message = json.loads(pack_telemetry(telemetry)[1])
    located = json.loads(pack_localization(localization)[1])
    page = ({key: located[key] for key in ("converged", "estimate", "std_x_m", "std_y_m", "std_theta_rad",
                                           "sim_time_s")} if located["active"] else None)
    return json.loads(json.dumps({**message, "camera_pose": None, "localization": page}))


class PageBackend:
    """The page's side with one telemetry message in the shared memory; records the commands."""

    def __init__(self, reading: dict[str, Any]) -> None:
        self.reading, self.clock, self.sent = reading, 0.0, []

    def now(self) -> float:
        return self.clock

    def wait_until(self, t_s: float) -> bool:
        self.clock = t_s
        return True

    def read(self) -> dict[str, Any]:
        return self.reading

    def send(self, linear_mps: float, angular_radps: float) -> None:
        self.sent.append((linear_mps, angular_radps))

    def skill(self, name: str, parameters: dict[str, Any], wait: bool = True) -> str:
        return "SUCCEEDED"

    def report(self, x_m: float, y_m: float, t_s: float) -> None:
        pass

    def limits(self) -> tuple[float, float, float]:
        return 0.5, 1.5, 60.0


def test_every_documented_reading_comes_from_the_telemetry_the_page_relays() -> None:
    ranges = [4.0] * 181
    ranges[90] = 0.21  # straight ahead: touching the body (radius 0.2 m)
    telemetry = robot_pb2.Telemetry(
        odometry=robot_pb2.Odometry(pose=robot_pb2.Pose2D(x_m=1.25, y_m=-0.5, theta_rad=0.3), linear_mps=0.2,
                                    angular_radps=-0.1),
        ground_truth=robot_pb2.Pose2D(x_m=9.0, y_m=9.0, theta_rad=1.0),
        sonar=robot_pb2.SonarReading(ranges_m=[0.5, 1.25, 3.0, 2.0, 2.5, 0.75, 1.5, 4.0]),
        laser=robot_pb2.LaserScan(angle_min_rad=-math.pi / 2, angle_increment_rad=math.pi / 180, ranges_m=ranges),
        battery=robot_pb2.Battery(charge=0.73),
        line=robot_pb2.LineSensorReading(values=[0.0, 0.1, 0.9, 1.0, 0.0]))
    localization = robot_pb2.LocalizationUpdate(active=True, converged=True,
                                                estimate=robot_pb2.Pose2D(x_m=2.9, y_m=-0.2, theta_rad=2.5),
                                                std_x_m=0.03, std_y_m=0.04,
                                                ground_truth=robot_pb2.Pose2D(x_m=2.95, y_m=-0.25))
    reading = relayed(telemetry, localization)
    assert "9.0" not in json.dumps(reading) and "2.95" not in json.dumps(reading)  # no truth reaches the program

    api = load_api()
    backend = PageBackend(reading)
    robot = api.attach(backend)
    assert robot.tick()
    odometry = robot.odometry()
    assert (odometry.x_m, odometry.y_m, odometry.theta_rad, odometry.linear_mps, odometry.angular_radps) == \
        (1.25, -0.5, 0.3, 0.2, -0.1)
    assert robot.sonar() == [0.5, 1.25, 3.0, 2.0, 2.5, 0.75, 1.5, 4.0]
    scan = robot.laser()
    assert len(scan.ranges_m) == 181 and abs(scan.angle(90)) < 1e-9
    assert robot.front_distance() == 0.21 and robot.bumper()
    assert robot.battery() == 0.73
    assert robot.line() == [0.0, 0.1, 0.9, 1.0, 0.0]
    assert robot.line_position() is not None and robot.line_position() < 0  # the tape is right of the middle
    located = robot.localization()
    assert located is not None and located.converged and (located.x_m, located.y_m) == (2.9, -0.2)
    assert abs(located.std_m - 0.05) < 1e-9

    robot.set_velocity(0.3, 0.5)
    assert robot.sleep(0.2)  # keeps ticking with the command in force
    assert backend.sent[-1] == (0.3, 0.5)


def test_without_a_line_in_the_scene_or_a_localization_running_the_api_says_none() -> None:
    telemetry = robot_pb2.Telemetry(battery=robot_pb2.Battery(charge=1.0))
    reading = relayed(telemetry, robot_pb2.LocalizationUpdate(active=False))
    robot = load_api().attach(PageBackend(reading))
    assert robot.tick()
    assert robot.line() is None and robot.line_position() is None and robot.localization() is None
    assert robot.sonar() == [] and robot.front_distance() == math.inf and not robot.bumper()
