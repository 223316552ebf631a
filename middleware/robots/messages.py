"""Translation of the robot's gRPC messages into what the browser receives (packed once per message)."""

from __future__ import annotations

import json
import struct
import time

from protos.telelab.v1 import robot_pb2


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


def pack_telemetry(telemetry: robot_pb2.Telemetry) -> str:
    """A telemetry text message; the ground truth stays in the middleware (it is for grading)."""
    odometry = telemetry.odometry
    return json.dumps(
        {
            "type": "telemetry",
            "tick": telemetry.tick,
            "sim_time_s": telemetry.sim_time_s,
            "capture_unix_s": telemetry.capture_unix_s,
            "last_applied_sequence": telemetry.last_applied_sequence,
            "deadman_stopped": telemetry.deadman_stopped,
            "odometry": {
                "pose": pose_dict(odometry.pose),
                "linear_mps": odometry.linear_mps,
                "angular_radps": odometry.angular_radps,
            },
            "sonar": {"ranges_m": [round(r, 4) for r in telemetry.sonar.ranges_m]},
            "laser": {
                "angle_min_rad": telemetry.laser.angle_min_rad,
                "angle_increment_rad": telemetry.laser.angle_increment_rad,
                "ranges_m": [round(r, 4) for r in telemetry.laser.ranges_m],
            },
        },
        separators=(",", ":"),
    )


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
    }
