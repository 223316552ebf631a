"""Immutable records the world's loop publishes; any thread may read them."""

from __future__ import annotations

from dataclasses import dataclass

from skill_server.sim.battery import FULL_BATTERY, BatteryState
from skill_server.sim.camera import CameraSpec
from skill_server.sim.floor_line import LineSensorSpec
from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.odometry import OdometryReading
from skill_server.sim.panels import PanelSpec
from skill_server.sim.robot_model import RobotSpec
from skill_server.sim.scenes import SceneBox
from skill_server.sim.sonar import SonarGeometry


@dataclass(frozen=True)
class RobotSnapshot:
    """The robot's state after one control tick."""

    tick: int
    sim_time_s: float
    capture_unix_s: float
    last_applied_sequence: int
    odometry: OdometryReading
    ground_truth: Pose2D
    sonar_ranges_m: tuple[float, ...]
    laser_ranges_m: tuple[float, ...]
    deadman_stopped: bool
    commanded_linear_mps: float  # after the acceleration ramp
    commanded_angular_radps: float
    battery: BatteryState = FULL_BATTERY
    line_readings: tuple[float, ...] = ()  # the line sensor's cells, left to right (none: the scene has no line)


@dataclass(frozen=True)
class CameraFrame:
    """One camera image, encoded once, with the metadata a viewer needs to place it in time."""

    frame_sequence: int
    capture_unix_s: float
    sim_time_s: float
    last_applied_sequence: int
    pose_at_capture: Pose2D  # odometry pose when the image was rendered
    width_px: int
    height_px: int
    jpeg: bytes


@dataclass(frozen=True)
class RobotDescription:
    """What GetRobotInfo reports: the robot's figures, sensors and scene."""

    scene_name: str
    spec: RobotSpec
    deadman_timeout_s: float
    camera: CameraSpec
    sonars: tuple[SonarGeometry, ...]
    laser: LaserSpec
    scene_boxes: tuple[SceneBox, ...]
    panels: tuple[PanelSpec, ...] = ()  # the resources' panels, in the order a console places them
    line_sensor: LineSensorSpec | None = None  # where its cells look (the scene has a line to read)
