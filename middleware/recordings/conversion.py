"""A recording's messages as the hub packed them for viewers (JSON text, camera frames) back into the robot's
protobuf messages, and a second of them written to an MCAP part: the writer child's work (writer.py, keeping.py),
never the worker's."""

from __future__ import annotations

import json
from typing import Any

from google.protobuf.message import Message

from middleware.recordings import channels, files
from middleware.recordings.files import FLUSH_S
from middleware.robots.messages import unpack_camera_frame
from protos.telelab.v1 import robot_pb2

TELEMETRY, LOCALIZATION, CAMERA = "telemetry", "localization", "camera"
Kept = tuple[str, Any, int]  # (what, the hub's packed message, received unix ns): kept on the loop as it came
Record = tuple[str, bytes, int]  # (topic, a serialized protobuf message of the topic's type, log time unix ns)
CommandRow = tuple[float, int, int, str, str, str, bool, str]  # sent_unix_s, user, sequence, source, action,
# detail (JSON), accepted, outcome: a recorded_commands row


def write_second(part: files.PartWriter, kept: list[Kept], records: list[Record], commands: list[CommandRow]) -> None:
    """Adds a second's messages to the part (a files.PartWriter) and closes the chunk (fsync): records as they are,
    hub messages and command rows as the robot's and the command log's protobuf messages. Messages that waited longer
    (the writer starting, a slow disk) go in a chunk per second of their arrival, so no chunk holds more than a
    second of the session."""
    timeline: list[tuple[int, int, Any]] = [(received_ns, 0, (what, payload)) for what, payload, received_ns in kept]
    timeline += [(int(row[0] * 1e9), 1, row) for row in commands]
    timeline += [(at_ns, 2, record) for *record, at_ns in records]
    timeline.sort(key=lambda item: (item[0], item[1]))
    chunk_started_ns = timeline[0][0] if timeline else 0
    for at_ns, kind, item in timeline:
        if at_ns - chunk_started_ns >= FLUSH_S * 1e9:
            part.flush()
            chunk_started_ns = at_ns
        if kind == 1:
            part.write(channels.COMMANDS, command_record(item), at_ns)
        elif kind == 2:
            part.write_serialized(item[0], item[1], at_ns)
        elif item[0] == TELEMETRY:
            _write_telemetry(part, item[1], at_ns)
        elif item[0] == LOCALIZATION:
            update_message = localization_from_packed(item[1])
            if update_message is not None and update_message.active:
                part.write(channels.LOCALIZATION, update_message, at_ns)
        elif item[0] == CAMERA:
            _write_camera(part, item[1], at_ns)
    part.flush()


def _write_telemetry(part: files.PartWriter, packed: str, received_ns: int) -> None:
    """One telemetry message as the hub packed it for viewers (with the truth's pose) back into the robot's
    messages: the poses exactly, sonar and laser ranges to the 0.1 mm the hub keeps."""
    try:
        message = json.loads(packed)
    except ValueError:
        return
    capture = message.get("capture_unix_s")
    at = int(capture * 1e9) if isinstance(capture, int | float) and capture > 0 else received_ns
    odometry = message.get("odometry") or {}
    sonar = message.get("sonar") or {}
    laser = message.get("laser") or {}
    part.write(channels.ODOMETRY, robot_pb2.Odometry(
        pose=_pose(odometry.get("pose")), linear_mps=_number(odometry.get("linear_mps")),
        angular_radps=_number(odometry.get("angular_radps"))), at)
    part.write(channels.GROUND_TRUTH, _pose(message.get("camera_pose")), at)
    part.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=_numbers(sonar.get("ranges_m"))), at)
    part.write(channels.LASER, robot_pb2.LaserScan(
        angle_min_rad=_number(laser.get("angle_min_rad")),
        angle_increment_rad=_number(laser.get("angle_increment_rad")), ranges_m=_numbers(laser.get("ranges_m"))), at)


def _write_camera(part: files.PartWriter, packed: bytes, received_ns: int) -> None:
    header, jpeg = unpack_camera_frame(packed)
    capture = _number(header.get("capture_unix_s"))
    part.write(channels.CAMERA, robot_pb2.CameraFrame(
        frame_sequence=int(_number(header.get("frame_sequence"))), capture_unix_s=capture,
        width_px=int(_number(header.get("width_px"))), height_px=int(_number(header.get("height_px"))), jpeg=jpeg),
        int(capture * 1e9) if capture > 0 else received_ns)


def command_record(row: CommandRow) -> Message:
    """A command log row as the recording's CommandRecord."""
    sent_unix_s, user_id, sequence, source, action, detail_text, accepted, outcome = row
    detail = json_object(detail_text)
    return channels.CommandRecord(
        sent_unix_s=sent_unix_s, user_id=user_id or 0, sequence=sequence, source=source, action=action,
        linear_mps=_number(detail.get("linear_mps")), angular_radps=_number(detail.get("angular_radps")),
        skill=str(detail.get("skill", "")), parameters_json=json.dumps(detail.get("parameters", {})),
        plan_name=str(detail.get("plan_name", "")), accepted=accepted, outcome=outcome)


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else 0.0


def _numbers(values: object) -> list[float]:
    return [float(v) for v in values if isinstance(v, int | float)] if isinstance(values, list) else []


def _pose(value: object) -> robot_pb2.Pose2D:
    """A packed pose ({x_m, y_m, theta_rad}) as the robot's message."""
    if not isinstance(value, dict):
        return robot_pb2.Pose2D()
    return robot_pb2.Pose2D(x_m=float(value.get("x_m", value.get("x", 0.0)) or 0.0),
                            y_m=float(value.get("y_m", value.get("y", 0.0)) or 0.0),
                            theta_rad=float(value.get("theta_rad", value.get("theta", 0.0)) or 0.0))


def json_object(text: str) -> dict[str, Any]:
    """The JSON object text holds, or {}."""
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def localization_from_packed(text: str) -> robot_pb2.LocalizationUpdate | None:
    """The hub's packed localization message (with the truth) as the robot's own message again."""
    try:
        message = json.loads(text)
    except ValueError:
        return None
    navigation = message.get("navigation") or {}
    return robot_pb2.LocalizationUpdate(
        sim_time_s=float(message.get("sim_time_s", 0.0)), active=bool(message.get("active")),
        converged=bool(message.get("converged")), estimate=_pose(message.get("estimate")),
        std_x_m=float(message.get("std_x_m") or 0.0), std_y_m=float(message.get("std_y_m") or 0.0),
        std_theta_rad=float(message.get("std_theta_rad") or 0.0), odometry=_pose(message.get("odometry")),
        ground_truth=_pose(message.get("ground_truth")),
        position_error_m=float(message.get("position_error_m") or 0.0),
        navigation_pose=_pose(navigation.get("pose")), navigation_source=str(navigation.get("source") or ""))
