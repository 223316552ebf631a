"""Translation of the robot's gRPC messages into what the browser receives (packed once per message)."""

from __future__ import annotations

import base64
import json
import struct
import time
from collections.abc import Iterable

import numpy

from protos.telelab.v1 import robot_pb2

PLANNED_PATH_POINTS = 64  # a goal's path as the page gets it: the robot caps it so, and nothing else is trusted


def pose_dict(pose: robot_pb2.Pose2D) -> dict[str, float]:
    """A pose as JSON-ready numbers."""
    return {"x_m": pose.x_m, "y_m": pose.y_m, "theta_rad": pose.theta_rad}


def pack_camera_frame(frame: robot_pb2.CameraFrame) -> bytes:
    """One binary WebSocket message: 4-byte big-endian header length, JSON header, JPEG bytes."""
    header = json.dumps(
        {
            "frame_sequence": frame.frame_sequence,
            "capture_unix_s": frame.capture_unix_s,
            "sim_time_s": frame.sim_time_s,
            "sent_unix_s": time.time(),
            "last_applied_sequence": frame.last_applied_sequence,
            "pose_at_capture": pose_dict(frame.pose_at_capture),
            "width_px": frame.width_px,
            "height_px": frame.height_px,
        },
        separators=(",", ":"),
    ).encode()
    return struct.pack(">I", len(header)) + header + frame.jpeg


def unpack_camera_frame(message: bytes) -> tuple[dict[str, object], bytes]:
    """The header and JPEG of a packed camera message (the inverse of pack_camera_frame)."""
    (length,) = struct.unpack(">I", message[:4])
    return json.loads(message[4 : 4 + length]), message[4 + length :]


def battery_dict(battery: robot_pb2.Battery) -> dict[str, object]:
    """The battery's charge (0..1), whether it charges at the dock, and whether it is empty."""
    return {"charge": round(battery.charge, 4), "charging": battery.charging, "empty": battery.empty}


def limits_dict(limits: robot_pb2.Limits) -> dict[str, float]:
    """The limits in force and the ranges the robot accepts."""
    return {"max_linear_mps": limits.max_linear_mps, "max_angular_radps": limits.max_angular_radps,
            "watchdog_s": limits.watchdog_s, "robot_max_linear_mps": limits.robot_max_linear_mps,
            "robot_max_angular_radps": limits.robot_max_angular_radps, "min_watchdog_s": limits.min_watchdog_s,
            "max_watchdog_s": limits.max_watchdog_s}


_COMPACT = (",", ":")


def rounded(values: Iterable[float], digits: int) -> list[float]:
    """values rounded to digits decimals, as JSON-ready floats: a laser's 181 ranges ten times a second per robot
    took Python's round() a third of a telemetry message's packing; numpy rounds them at once (the same numbers but
    for the last digit of an exact tie, which a 0.1 mm reading does not carry)."""
    array = numpy.fromiter(values, dtype=float)
    return numpy.round(array, digits).tolist() if array.size else []


def _with_fields(packed: str, fields: str) -> str:
    """A compact JSON object's text with more fields' text (`"key":value,...`) appended at its end."""
    return f"{packed[:-1]},{fields}}}" if packed != "{}" else f"{{{fields}}}"


def pack_telemetry(telemetry: robot_pb2.Telemetry) -> tuple[str, str]:
    """The telemetry message twice, encoded once: with `camera_pose` (where the robot truly stands, which a
    camera drawn in the browser needs: a camera shows the world as it is) and with `camera_pose` null (for a
    viewer in a graded run, whose drawn camera gives way to the server's). Nothing else of the truth leaves."""
    odometry = telemetry.odometry
    message = {
        "type": "telemetry",
        "tick": telemetry.tick,
        "sim_time_s": telemetry.sim_time_s,
        "capture_unix_s": telemetry.capture_unix_s,
        "last_applied_sequence": telemetry.last_applied_sequence,
        "deadman_stopped": telemetry.deadman_stopped,
        "battery": battery_dict(telemetry.battery),
        "odometry": {
            "pose": pose_dict(odometry.pose),
            "linear_mps": odometry.linear_mps,
            "angular_radps": odometry.angular_radps,
        },
        "sonar": {"ranges_m": rounded(telemetry.sonar.ranges_m, 4)},
        "laser": {
            "angle_min_rad": telemetry.laser.angle_min_rad,
            "angle_increment_rad": telemetry.laser.angle_increment_rad,
            "ranges_m": rounded(telemetry.laser.ranges_m, 4),
        },
        "line": {"values": rounded(telemetry.line.values, 3)},
    }
    packed = json.dumps(message, separators=_COMPACT)  # the readings once; the two versions differ in their end
    truth = json.dumps(pose_dict(telemetry.ground_truth), separators=_COMPACT)
    return _with_fields(packed, f'"camera_pose":{truth}'), _with_fields(packed, '"camera_pose":null')


def robot_info_dict(info: robot_pb2.RobotInfo) -> dict[str, object]:
    """The robot's description as the console needs it."""
    return {
        "robot_name": info.robot_name,
        "scene_name": info.scene_name,
        "max_linear_mps": info.max_linear_mps,
        "max_angular_radps": info.max_angular_radps,
        "deadman_timeout_s": info.deadman_timeout_s,
        "wheel_base_m": info.wheel_base_m,
        "body_radius_m": info.body_radius_m,
        "camera_width_px": info.camera_width_px,
        "camera_height_px": info.camera_height_px,
        "camera_hfov_deg": info.camera_hfov_deg,
        "sonar_count": len(info.sonars),
        "laser_beam_count": info.laser.beam_count,
        "sonars": [
            {"mount_angle_rad": s.mount_angle_rad, "cone_half_angle_rad": s.cone_half_angle_rad,
             "min_range_m": s.min_range_m, "max_range_m": s.max_range_m}
            for s in info.sonars
        ],
        "laser": {
            "angle_min_rad": info.laser.angle_min_rad, "angle_max_rad": info.laser.angle_max_rad,
            "beam_count": info.laser.beam_count, "min_range_m": info.laser.min_range_m,
            "max_range_m": info.laser.max_range_m,
        },
        "scene_boxes": [
            {"name": b.name, "center_x_m": b.center_x_m, "center_y_m": b.center_y_m, "half_x_m": b.half_x_m,
             "half_y_m": b.half_y_m, "yaw_rad": b.yaw_rad}
            for b in info.scene_boxes
        ],
        "line_sensor": ({"ahead_m": info.line_sensor.ahead_m, "offsets_m": list(info.line_sensor.offsets_m)}
                        if info.HasField("line_sensor") else None),
    }


_PARAMETER_TYPES = {
    robot_pb2.PARAMETER_TYPE_DOUBLE: "double",
    robot_pb2.PARAMETER_TYPE_INT: "int",
    robot_pb2.PARAMETER_TYPE_BOOL: "bool",
    robot_pb2.PARAMETER_TYPE_ENUM: "enum",
}


_VIEWS = {robot_pb2.CONSOLE_VIEW_DRIVE: "drive", robot_pb2.CONSOLE_VIEW_NAVIGATE: "navigate",
          robot_pb2.CONSOLE_VIEW_SENSE: "sense", robot_pb2.CONSOLE_VIEW_CHAT: "chat"}
_STREAMS = {robot_pb2.ROBOT_STREAM_CAMERA: "camera", robot_pb2.ROBOT_STREAM_TELEMETRY: "telemetry",
            robot_pb2.ROBOT_STREAM_LOCALIZATION: "localization"}


def panel_descriptor(robot_name: str, panel: robot_pb2.PanelDescription) -> dict[str, object]:
    """A panel the robot describes, as the console places it: its stream becomes the channel of the robot's socket
    of that name (None for a panel that asks for what it shows); a view the robot leaves unspecified is Sense."""
    stream = _STREAMS.get(panel.stream)
    return {"id": panel.id, "kind": panel.kind, "title": panel.title,
            "channel": f"/ws/robots/{robot_name}/{stream}" if stream else None, "help": panel.help,
            "tab": _VIEWS.get(panel.view, "sense")}


def parameter_schema_dict(schema: robot_pb2.ParameterSchema) -> dict[str, object]:
    """One parameter's schema as the skill panel needs it."""
    kind = _PARAMETER_TYPES.get(schema.type, "string")
    default: object = schema.default_value
    if kind == "enum":
        choices = list(schema.choices)
        index = int(schema.default_value)
        default = choices[index] if 0 <= index < len(choices) else (choices[0] if choices else "")
    elif kind == "int":
        default = int(schema.default_value)
    elif kind == "bool":
        default = bool(schema.default_value)
    return {
        "name": schema.name, "type": kind, "unit": schema.unit, "minimum": schema.minimum,
        "maximum": schema.maximum, "default": default, "help": schema.help, "choices": list(schema.choices),
    }


def _parameter_value(value: robot_pb2.ParameterValue) -> object:
    kind = value.WhichOneof("kind")
    return getattr(value, kind) if kind else None


def feedback_dict(feedback: robot_pb2.GoalFeedback) -> dict[str, object]:
    """A goal's feedback as JSON-ready data."""
    return {
        "sim_time_s": feedback.sim_time_s,
        "state": feedback.state,
        "progress": feedback.progress,
        "distance_error_m": feedback.distance_error_m,
        "heading_error_rad": feedback.heading_error_rad,
        "pose": pose_dict(feedback.pose),
        "pose_source": feedback.pose_source,
        "values": dict(feedback.values),
        "planned_path": [[point.x_m, point.y_m] for point in feedback.planned_path[:PLANNED_PATH_POINTS]],
    }


def goal_dict(goal: robot_pb2.GoalState) -> dict[str, object]:
    """A goal's state as JSON-ready data; the status is the lower-case name of the enum value."""
    status = robot_pb2.GoalStatus.Name(goal.status).removeprefix("GOAL_STATUS_").lower()
    return {
        "goal_id": goal.goal_id,
        "skill": goal.skill,
        "motor": goal.motor,
        "status": status,
        "parameters": {name: _parameter_value(value) for name, value in goal.parameters.items()},
        "error_code": goal.error_code,
        "message": goal.message,
        "goal_reached": goal.goal_reached,
        "feedback": feedback_dict(goal.feedback) if goal.HasField("feedback") else None,
    }


FINAL_GOAL_STATUSES = {"succeeded", "canceled", "aborted"}


def goal_update_message(update: robot_pb2.GoalUpdate) -> dict[str, object]:
    """One WatchGoal update as a socket message."""
    kind = update.WhichOneof("update")
    if kind == "state":
        return {"type": "goal", "goal": goal_dict(update.state)}
    if kind == "event":
        name = robot_pb2.GoalEventKind.Name(update.event.kind).removeprefix("GOAL_EVENT_KIND_").lower()
        return {"type": "goal_event", "kind": name, "message": update.event.message,
                "sim_time_s": update.event.sim_time_s}
    return {"type": "goal_feedback", "feedback": feedback_dict(update.feedback)}


def pack_localization(update: robot_pb2.LocalizationUpdate) -> tuple[str, str]:
    """The localization message twice, packed once each: with the ground truth, and without it."""
    message: dict[str, object] = {
        "type": "localization",
        "sim_time_s": update.sim_time_s,
        "active": update.active,
        "converged": update.converged,
        "estimate": pose_dict(update.estimate),
        "std_x_m": update.std_x_m,
        "std_y_m": update.std_y_m,
        "std_theta_rad": update.std_theta_rad,
        "odometry": pose_dict(update.odometry),
        "navigation": ({"pose": pose_dict(update.navigation_pose), "source": update.navigation_source}
                       if update.navigation_source else None),
        "update_duration_ms": update.update_duration_ms,
        "particles": [[round(p.x_m, 3), round(p.y_m, 3), round(p.theta_rad, 3), p.weight] for p in update.particles],
    }
    hidden = {"ground_truth": None, "position_error_m": None, "heading_error_rad": None,
              "odometry_position_error_m": None, "odometry_heading_error_rad": None}
    shown = {
        "ground_truth": pose_dict(update.ground_truth),
        "position_error_m": update.position_error_m if update.active else None,
        "heading_error_rad": update.heading_error_rad if update.active else None,
        "odometry_position_error_m": update.odometry_position_error_m,
        "odometry_heading_error_rad": update.odometry_heading_error_rad,
    }
    packed = json.dumps(message, separators=_COMPACT)  # the particles once; the two versions differ in their end
    return (_with_fields(packed, json.dumps(shown, separators=_COMPACT)[1:-1]),
            _with_fields(packed, json.dumps(hidden, separators=_COMPACT)[1:-1]))


def map_dict(grid: robot_pb2.OccupancyGrid) -> dict[str, object]:
    """The occupancy grid with its cells in base64."""
    return {
        "resolution_m": grid.resolution_m,
        "origin_x_m": grid.origin_x_m,
        "origin_y_m": grid.origin_y_m,
        "width_cells": grid.width_cells,
        "height_cells": grid.height_cells,
        "cells_b64": base64.b64encode(grid.cells).decode(),
        "scans_integrated": grid.scans_integrated,
        "sim_time_s": grid.sim_time_s,
    }
