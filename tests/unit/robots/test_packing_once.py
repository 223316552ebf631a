"""A telemetry or localization message is encoded once for its two versions (with the truth, without it): the two
texts share every byte but the truth's fields at their end, and the readings keep the digits the browser gets."""

from __future__ import annotations

import json
import math
import random

from middleware.robots.messages import pack_localization, pack_telemetry, rounded
from protos.telelab.v1 import robot_pb2


def a_scan(seed: int) -> robot_pb2.Telemetry:
    """A robot's telemetry with sonar, laser (some beams out of range) and line readings."""
    rng = random.Random(seed)
    telemetry = robot_pb2.Telemetry(tick=seed, sim_time_s=rng.uniform(0, 100), capture_unix_s=1.7e9 + seed)
    telemetry.odometry.pose.CopyFrom(robot_pb2.Pose2D(x_m=rng.uniform(-5, 5), y_m=1.0, theta_rad=0.2))
    telemetry.ground_truth.CopyFrom(robot_pb2.Pose2D(x_m=rng.uniform(-5, 5), y_m=1.1, theta_rad=0.25))
    telemetry.sonar.ranges_m.extend(rng.uniform(0.0, 5.0) for _ in range(16))
    telemetry.laser.ranges_m.extend(rng.choice([rng.uniform(0.0, 8.0), math.inf]) for _ in range(181))
    telemetry.line.values.extend(rng.random() for _ in range(5))
    return telemetry


def test_the_two_telemetry_versions_differ_only_in_the_camera_pose_at_their_end() -> None:
    for seed in range(20):
        telemetry = a_scan(seed)
        shown, hidden = pack_telemetry(telemetry)
        body = shown[: shown.index(',"camera_pose":')]
        assert hidden == body + ',"camera_pose":null}'
        assert json.loads(shown)["camera_pose"] == {"x_m": telemetry.ground_truth.x_m, "y_m": 1.1,
                                                    "theta_rad": 0.25}


def test_readings_keep_four_decimals_as_python_rounds_them() -> None:
    for seed in range(20):
        telemetry = a_scan(seed)
        message = json.loads(pack_telemetry(telemetry)[1])
        assert message["laser"]["ranges_m"] == [round(r, 4) for r in telemetry.laser.ranges_m]
        assert message["sonar"]["ranges_m"] == [round(r, 4) for r in telemetry.sonar.ranges_m]
        assert message["line"]["values"] == [round(v, 3) for v in telemetry.line.values]
    assert rounded([], 4) == []
    assert rounded([0.12345678, 2.5], 2) == [0.12, 2.5]


def test_localization_shows_the_truth_in_one_version_only() -> None:
    update = robot_pb2.LocalizationUpdate(sim_time_s=3.0, active=True, position_error_m=0.2)
    update.ground_truth.CopyFrom(robot_pb2.Pose2D(x_m=1.0, y_m=2.0, theta_rad=0.5))
    update.particles.add(x_m=1.0001, y_m=2.0, theta_rad=0.1, weight=0.5)
    shown, hidden = (json.loads(text) for text in pack_localization(update))
    assert shown["ground_truth"] == {"x_m": 1.0, "y_m": 2.0, "theta_rad": 0.5}
    assert shown["position_error_m"] == 0.2 and shown["particles"] == [[1.0, 2.0, 0.1, 0.5]]
    truth = ("ground_truth", "position_error_m", "heading_error_rad", "odometry_position_error_m",
             "odometry_heading_error_rad")
    assert all(hidden[key] is None for key in truth)
    assert {k: v for k, v in shown.items() if k not in truth} == {k: v for k, v in hidden.items() if k not in truth}
