"""Proto <-> domain translation for the Robot service (no rules here, only shapes)."""

from __future__ import annotations

from protos.telelab.v1 import robot_pb2
from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.snapshots import CameraFrame, RobotSnapshot
from skill_server.skills.schema import ParameterType, SkillDescription

_PARAMETER_TYPES = {
    ParameterType.DOUBLE: robot_pb2.PARAMETER_TYPE_DOUBLE,
    ParameterType.INT: robot_pb2.PARAMETER_TYPE_INT,
    ParameterType.BOOL: robot_pb2.PARAMETER_TYPE_BOOL,
    ParameterType.ENUM: robot_pb2.PARAMETER_TYPE_ENUM,
}


def pose_to_proto(pose: Pose2D) -> robot_pb2.Pose2D:
    return robot_pb2.Pose2D(x_m=pose.x_m, y_m=pose.y_m, theta_rad=pose.theta_rad)


def telemetry_to_proto(snapshot: RobotSnapshot, laser: LaserSpec) -> robot_pb2.Telemetry:
    return robot_pb2.Telemetry(
        tick=snapshot.tick,
        sim_time_s=snapshot.sim_time_s,
        capture_unix_s=snapshot.capture_unix_s,
        last_applied_sequence=snapshot.last_applied_sequence,
        odometry=robot_pb2.Odometry(
            pose=pose_to_proto(snapshot.odometry.pose),
            linear_mps=snapshot.odometry.linear_mps,
            angular_radps=snapshot.odometry.angular_radps,
        ),
        ground_truth=pose_to_proto(snapshot.ground_truth),
        sonar=robot_pb2.SonarReading(ranges_m=snapshot.sonar_ranges_m),
        laser=robot_pb2.LaserScan(
            angle_min_rad=laser.angle_min_rad,
            angle_increment_rad=laser.angle_increment_rad,
            ranges_m=snapshot.laser_ranges_m,
        ),
        deadman_stopped=snapshot.deadman_stopped,
    )


def frame_to_proto(frame: CameraFrame) -> robot_pb2.CameraFrame:
    return robot_pb2.CameraFrame(
        frame_sequence=frame.frame_sequence,
        capture_unix_s=frame.capture_unix_s,
        sim_time_s=frame.sim_time_s,
        last_applied_sequence=frame.last_applied_sequence,
        pose_at_capture=pose_to_proto(frame.pose_at_capture),
        width_px=frame.width_px,
        height_px=frame.height_px,
        jpeg=frame.jpeg,
    )


def skill_to_proto(skill: SkillDescription) -> robot_pb2.SkillDescription:
    return robot_pb2.SkillDescription(
        name=skill.name,
        title=skill.title,
        help=skill.help,
        parameters=[
            robot_pb2.ParameterSchema(
                name=p.name,
                type=_PARAMETER_TYPES[p.type],
                unit=p.unit,
                minimum=p.minimum,
                maximum=p.maximum,
                default_value=p.default,
                help=p.help,
                choices=list(p.choices),
            )
            for p in skill.parameters
        ],
    )
