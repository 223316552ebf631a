"""Proto <-> domain translation for the Robot service: shapes only, no rules (the one place that does it)."""

from __future__ import annotations

import math
from collections.abc import Mapping

from protos.telelab.v1 import robot_pb2
from skill_server.errors import InvalidParameter
from skill_server.goals import EventKind, GoalEvent, GoalFeedback, GoalSnapshot, GoalStatus
from skill_server.robot import (
    BatteryState,
    CameraFrame,
    DriveAck,
    FloorPatch,
    GoalUpdate,
    LaserSpec,
    LocalizationEstimate,
    MotionLimits,
    NavigationPose,
    NumberedEvent,
    PanelSpec,
    Pose2D,
    PublishedGrid,
    RobotDescription,
    RobotHealth,
    RobotSnapshot,
    SceneDescription,
    SkillEntry,
    TrackEvent,
    TrackState,
)
from skill_server.schema import ParameterType

_PARAMETER_TYPES = {
    ParameterType.DOUBLE: robot_pb2.PARAMETER_TYPE_DOUBLE,
    ParameterType.INT: robot_pb2.PARAMETER_TYPE_INT,
    ParameterType.BOOL: robot_pb2.PARAMETER_TYPE_BOOL,
    ParameterType.ENUM: robot_pb2.PARAMETER_TYPE_ENUM,
}

_STATUS = {status: getattr(robot_pb2, f"GOAL_STATUS_{status.name}") for status in GoalStatus}
_EVENT = {kind: getattr(robot_pb2, f"GOAL_EVENT_KIND_{kind.name}") for kind in EventKind}


def rate_from_proto(field: str, requested: float, default: float, maximum: float, unit: str) -> float:
    """A stream's asked rate: 0 (proto3's unset) means the default; anything else must be in (0, maximum]."""
    if requested == 0:
        return default
    if not math.isfinite(requested) or not 0 < requested <= maximum:
        raise InvalidParameter(
            field, f"{field} must be a finite number above 0 and at most {maximum:g} {unit} (0 means {default:g})"
        )
    return requested


def pose_from_proto(pose: robot_pb2.Pose2D) -> Pose2D:
    """A pose as the robot core takes it (checked there)."""
    return Pose2D(pose.x_m, pose.y_m, pose.theta_rad)


def pose_to_proto(pose: Pose2D) -> robot_pb2.Pose2D:
    return robot_pb2.Pose2D(x_m=pose.x_m, y_m=pose.y_m, theta_rad=pose.theta_rad)


_VIEWS = {"drive": robot_pb2.CONSOLE_VIEW_DRIVE, "navigate": robot_pb2.CONSOLE_VIEW_NAVIGATE,
          "sense": robot_pb2.CONSOLE_VIEW_SENSE, "chat": robot_pb2.CONSOLE_VIEW_CHAT}
_STREAMS = {None: robot_pb2.ROBOT_STREAM_UNSPECIFIED, "camera": robot_pb2.ROBOT_STREAM_CAMERA,
            "telemetry": robot_pb2.ROBOT_STREAM_TELEMETRY, "localization": robot_pb2.ROBOT_STREAM_LOCALIZATION}


def panel_to_proto(panel: PanelSpec) -> robot_pb2.PanelDescription:
    """One resource's panel as the contract describes it."""
    return robot_pb2.PanelDescription(id=panel.id, kind=panel.kind, title=panel.title, help=panel.help,
                                      view=_VIEWS[panel.view], stream=_STREAMS[panel.stream])


def robot_info_to_proto(robot_name: str, info: RobotDescription) -> robot_pb2.RobotInfo:
    """The robot, its sensors and its scene."""
    spec = info.spec
    return robot_pb2.RobotInfo(
        robot_name=robot_name,
        scene_name=info.scene_name,
        wheel_base_m=spec.wheel_base_m,
        wheel_radius_m=spec.wheel_radius_m,
        body_radius_m=spec.body_radius_m,
        max_linear_mps=spec.max_linear_mps,
        max_angular_radps=spec.max_angular_radps,
        deadman_timeout_s=info.deadman_timeout_s,
        camera_hfov_deg=info.camera.hfov_deg,
        camera_width_px=info.camera.width_px,
        camera_height_px=info.camera.height_px,
        sonars=[
            robot_pb2.SonarGeometry(
                mount_angle_rad=s.mount_angle_rad,
                cone_half_angle_rad=s.cone_half_angle_rad,
                min_range_m=s.min_range_m,
                max_range_m=s.max_range_m,
            )
            for s in info.sonars
        ],
        laser=robot_pb2.LaserGeometry(
            angle_min_rad=info.laser.angle_min_rad,
            angle_max_rad=info.laser.angle_max_rad,
            beam_count=info.laser.beam_count,
            min_range_m=info.laser.min_range_m,
            max_range_m=info.laser.max_range_m,
            height_m=info.laser.height_m,
        ),
        scene_boxes=[
            robot_pb2.SceneBox(
                name=b.name,
                center_x_m=b.center_x_m,
                center_y_m=b.center_y_m,
                half_x_m=b.half_x_m,
                half_y_m=b.half_y_m,
                yaw_rad=b.yaw_rad,
            )
            for b in info.scene_boxes
        ],
        panels=[panel_to_proto(panel) for panel in info.panels],
        line_sensor=(robot_pb2.LineSensorGeometry(ahead_m=info.line_sensor.ahead_m,
                                                  offsets_m=info.line_sensor.offsets_m)
                     if info.line_sensor is not None else None),
    )


_PATCH_KINDS = {
    "floor": robot_pb2.FLOOR_PATCH_KIND_FLOOR,
    "paint": robot_pb2.FLOOR_PATCH_KIND_PAINT,
    "grid": robot_pb2.FLOOR_PATCH_KIND_GRID,
    "track_line": robot_pb2.FLOOR_PATCH_KIND_TRACK_LINE,
    "track_point": robot_pb2.FLOOR_PATCH_KIND_TRACK_POINT,
}
_PART_SHAPES = {"box": robot_pb2.PART_SHAPE_BOX, "cylinder": robot_pb2.PART_SHAPE_CYLINDER,
                "sphere": robot_pb2.PART_SHAPE_SPHERE}


def _rgba(rgba: tuple[float, float, float, float]) -> robot_pb2.Rgba:
    return robot_pb2.Rgba(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])


def scene_to_proto(scene: SceneDescription, known_version: str = "") -> robot_pb2.SceneDescription:
    """The static world; only its version, marked unchanged, when the caller already holds that version."""
    if known_version == scene.version:
        return robot_pb2.SceneDescription(version=scene.version, unchanged=True)
    camera = scene.camera
    track = scene.track
    return robot_pb2.SceneDescription(
        version=scene.version,
        scene_name=scene.scene_name,
        floor=_patch_to_proto(scene.floor),
        marks=[_patch_to_proto(mark) for mark in scene.marks],
        blocks=[robot_pb2.SceneBlock(name=b.name, center_x_m=b.center_x_m, center_y_m=b.center_y_m, half_x_m=b.half_x_m,
                                     half_y_m=b.half_y_m, height_m=b.height_m, yaw_rad=b.yaw_rad, colour=_rgba(b.rgba))
                for b in scene.boxes],
        cylinders=[robot_pb2.SceneCylinder(name=c.name, center_x_m=c.center_x_m, center_y_m=c.center_y_m,
                                           radius_m=c.radius_m, height_m=c.height_m, colour=_rgba(c.rgba))
                   for c in scene.cylinders],
        track=None if track is None else robot_pb2.TrackLayout(
            a_x_m=track.a_x_m, a_y_m=track.a_y_m, b_x_m=track.b_x_m, b_y_m=track.b_y_m, round_trip=track.round_trip,
            arrival_radius_m=track.arrival_radius_m,
            lines=[robot_pb2.TrackLine(x1_m=line.x1_m, y1_m=line.y1_m, x2_m=line.x2_m, y2_m=line.y2_m,
                                       half_width_m=line.half_width_m) for line in track.lines]),
        spawn=pose_to_proto(scene.spawn),
        body_radius_m=scene.body_radius_m,
        robot_parts=[robot_pb2.RobotPart(
            link=part.link, shape=_PART_SHAPES[part.shape], size_x_m=part.size_m[0], size_y_m=part.size_m[1],
            size_z_m=part.size_m[2], position_m=robot_pb2.Vector3(x=part.position_m[0], y=part.position_m[1],
                                                                  z=part.position_m[2]),
            orientation=robot_pb2.Quaternion(x=part.orientation_xyzw[0], y=part.orientation_xyzw[1],
                                             z=part.orientation_xyzw[2], w=part.orientation_xyzw[3]),
            colour=_rgba(part.rgba)) for part in scene.robot_parts],
        camera=robot_pb2.CameraModel(
            width_px=camera.width_px, height_px=camera.height_px, hfov_deg=camera.hfov_deg, vfov_deg=camera.vfov_deg,
            near_m=camera.near_m, far_m=camera.far_m, mount_forward_m=camera.mount_forward_m,
            mount_height_m=camera.mount_height_m, mount_pitch_rad=camera.mount_pitch_rad,
            light_direction=robot_pb2.Vector3(x=camera.light_direction[0], y=camera.light_direction[1],
                                              z=camera.light_direction[2]),
            light_ambient=camera.light_ambient, light_diffuse=camera.light_diffuse,
            light_specular=camera.light_specular, specular_exponent=camera.specular_exponent,
            background=_rgba(camera.background_rgba), sample_offset_x_px=camera.sample_offset_px[0],
            sample_offset_y_px=camera.sample_offset_px[1]),
        laser=robot_pb2.LaserGeometry(
            angle_min_rad=scene.laser.angle_min_rad, angle_max_rad=scene.laser.angle_max_rad,
            beam_count=scene.laser.beam_count, min_range_m=scene.laser.min_range_m,
            max_range_m=scene.laser.max_range_m, height_m=scene.laser.height_m),
        sonar=robot_pb2.SonarRing(
            mount_radius_m=scene.sonar.mount_radius_m, height_m=scene.sonar.height_m,
            sonars=[robot_pb2.SonarGeometry(mount_angle_rad=s.mount_angle_rad,
                                            cone_half_angle_rad=s.cone_half_angle_rad, min_range_m=s.min_range_m,
                                            max_range_m=s.max_range_m) for s in scene.sonar.sonars]),
        room_cameras=[robot_pb2.RoomCamera(
            id=c.id, title=c.title, x_m=c.x_m, y_m=c.y_m, z_m=c.z_m, pan_rad=c.pan_rad, tilt_rad=c.tilt_rad,
            hfov_deg=c.hfov_deg, pan_range_rad=c.pan_range_rad, min_tilt_rad=c.min_tilt_rad,
            max_tilt_rad=c.max_tilt_rad, min_hfov_deg=c.min_hfov_deg, max_hfov_deg=c.max_hfov_deg)
            for c in scene.room_cameras],
    )


def _patch_to_proto(patch: FloorPatch) -> robot_pb2.FloorPatch:
    return robot_pb2.FloorPatch(center_x_m=patch.center_x_m, center_y_m=patch.center_y_m, half_x_m=patch.half_x_m,
                                half_y_m=patch.half_y_m, top_z_m=patch.top_z_m, colour=_rgba(patch.rgba),
                                kind=_PATCH_KINDS[patch.kind])


def drive_ack_to_proto(ack: DriveAck) -> robot_pb2.DriveAck:
    """The sequence in force and the velocities now commanded."""
    return robot_pb2.DriveAck(
        applied_sequence=ack.applied_sequence, linear_mps=ack.linear_mps, angular_radps=ack.angular_radps
    )


def battery_to_proto(battery: BatteryState) -> robot_pb2.Battery:
    """The battery's charge as telemetry carries it."""
    return robot_pb2.Battery(charge=battery.charge, charging=battery.charging, empty=battery.empty)


def limits_to_proto(limits: MotionLimits) -> robot_pb2.Limits:
    """The limits in force and the ranges SetLimits accepts."""
    return robot_pb2.Limits(
        max_linear_mps=limits.max_linear_mps, max_angular_radps=limits.max_angular_radps,
        watchdog_s=limits.watchdog_s, robot_max_linear_mps=limits.robot_max_linear_mps,
        robot_max_angular_radps=limits.robot_max_angular_radps, min_watchdog_s=limits.min_watchdog_s,
        max_watchdog_s=limits.max_watchdog_s)


def telemetry_to_proto(snapshot: RobotSnapshot, laser: LaserSpec, pose_only: bool = False) -> robot_pb2.Telemetry:
    pose = robot_pb2.Telemetry(
        tick=snapshot.tick,
        sim_time_s=snapshot.sim_time_s,
        capture_unix_s=snapshot.capture_unix_s,
        last_applied_sequence=snapshot.last_applied_sequence,
        odometry=robot_pb2.Odometry(
            pose=pose_to_proto(snapshot.odometry.pose),
            linear_mps=snapshot.odometry.linear_mps,
            angular_radps=snapshot.odometry.angular_radps,
        ),
        deadman_stopped=snapshot.deadman_stopped,
        battery=battery_to_proto(snapshot.battery),
    )
    if pose_only:
        return pose
    return robot_pb2.Telemetry(
        tick=snapshot.tick,
        sim_time_s=snapshot.sim_time_s,
        capture_unix_s=snapshot.capture_unix_s,
        last_applied_sequence=snapshot.last_applied_sequence,
        odometry=pose.odometry,
        ground_truth=pose_to_proto(snapshot.ground_truth),
        sonar=robot_pb2.SonarReading(ranges_m=snapshot.sonar_ranges_m),
        laser=robot_pb2.LaserScan(
            angle_min_rad=laser.angle_min_rad,
            angle_increment_rad=laser.angle_increment_rad,
            ranges_m=snapshot.laser_ranges_m,
        ),
        deadman_stopped=snapshot.deadman_stopped,
        battery=pose.battery,
        line=robot_pb2.LineSensorReading(values=snapshot.line_readings),
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


def skill_to_proto(entry: SkillEntry) -> robot_pb2.SkillDescription:
    skill = entry.description
    return robot_pb2.SkillDescription(
        name=skill.name,
        title=skill.title,
        help=skill.help,
        motor=entry.motor,
        estimates_pose=entry.estimates_pose,
        direct_drive=entry.direct_drive,
        skill_class=f"SKILL_CLASS_{entry.skill_class.upper()}",
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


def parameters_from_proto(values: Mapping[str, robot_pb2.ParameterValue]) -> dict[str, object]:
    """Plain Python values (float, int, bool, str) from the request's map; an empty value is refused."""
    plain: dict[str, object] = {}
    for name, value in values.items():
        kind = value.WhichOneof("kind")
        if kind is None:
            raise InvalidParameter(name, f"{name} has no value")
        plain[name] = getattr(value, kind)
    return plain


def parameter_to_proto(value: float | int | bool | str) -> robot_pb2.ParameterValue:
    """One validated value as a ParameterValue."""
    if isinstance(value, bool):
        return robot_pb2.ParameterValue(bool_value=value)
    if isinstance(value, int):
        return robot_pb2.ParameterValue(int_value=value)
    if isinstance(value, str):
        return robot_pb2.ParameterValue(string_value=value)
    return robot_pb2.ParameterValue(double_value=value)


def feedback_to_proto(feedback: GoalFeedback) -> robot_pb2.GoalFeedback:
    """A goal's feedback."""
    return robot_pb2.GoalFeedback(
        sim_time_s=feedback.sim_time_s,
        state=feedback.state,
        progress=feedback.progress,
        distance_error_m=feedback.distance_error_m,
        heading_error_rad=feedback.heading_error_rad,
        pose=pose_to_proto(feedback.pose),
        pose_source=feedback.pose_source,
        values={name: value for name, value in feedback.values if math.isfinite(value)},
        planned_path=[robot_pb2.Pose2D(x_m=x_m, y_m=y_m) for x_m, y_m in feedback.planned_path],
    )


def event_to_proto(index: int, event: GoalEvent) -> robot_pb2.GoalEvent:
    """One event with its position in the log."""
    return robot_pb2.GoalEvent(index=index, sim_time_s=event.sim_time_s, kind=_EVENT[event.kind],
                               message=event.message)


def goal_to_proto(goal: GoalSnapshot) -> robot_pb2.GoalState:
    """A goal's state."""
    return robot_pb2.GoalState(
        goal_id=goal.goal_id,
        skill=goal.skill,
        motor=goal.motor,
        status=_STATUS[goal.status],
        parameters={name: parameter_to_proto(value) for name, value in goal.parameters},
        accepted_sim_s=goal.accepted_sim_s,
        ended_sim_s=goal.ended_sim_s or 0.0,
        error_code=goal.error_code,
        message=goal.message,
        feedback=feedback_to_proto(goal.feedback),
        goal_reached=goal.goal_reached,
    )


def grid_to_proto(grid: PublishedGrid) -> robot_pb2.OccupancyGrid:
    """The environment model's published grid."""
    return robot_pb2.OccupancyGrid(
        resolution_m=grid.resolution_m,
        origin_x_m=grid.origin_x_m,
        origin_y_m=grid.origin_y_m,
        width_cells=grid.width_cells,
        height_cells=grid.height_cells,
        cells=grid.cells,
        scans_integrated=grid.scans_integrated,
        sim_time_s=grid.sim_time_s,
    )


def localization_to_proto(
    snapshot: RobotSnapshot, estimate: LocalizationEstimate | None, navigation: NavigationPose | None = None,
    max_particles: int = 0,
) -> robot_pb2.LocalizationUpdate:
    """The estimate beside odometry and ground truth, with their errors, and the pose the skills steer by."""
    truth, odometry = snapshot.ground_truth, snapshot.odometry.pose
    update = robot_pb2.LocalizationUpdate(
        sim_time_s=snapshot.sim_time_s,
        odometry=pose_to_proto(odometry),
        ground_truth=pose_to_proto(truth),
        odometry_position_error_m=truth.distance_to(odometry),
        odometry_heading_error_rad=abs(math.remainder(odometry.theta_rad - truth.theta_rad, 2 * math.pi)),
    )
    if navigation is not None:
        update.navigation_pose.CopyFrom(pose_to_proto(navigation.pose))
        update.navigation_source = navigation.source
    if estimate is None:
        return update
    pose = estimate.pose_at(odometry)
    update.active = True
    update.converged = estimate.converged
    update.estimate.CopyFrom(pose_to_proto(pose))
    update.std_x_m, update.std_y_m, update.std_theta_rad = estimate.std_x_m, estimate.std_y_m, estimate.std_theta_rad
    update.position_error_m = truth.distance_to(pose)
    update.heading_error_rad = abs(math.remainder(pose.theta_rad - truth.theta_rad, 2 * math.pi))
    update.update_duration_ms = estimate.update_duration_ms
    for x_m, y_m, theta_rad, weight in estimate.particles[:max_particles]:
        update.particles.add(x_m=x_m, y_m=y_m, theta_rad=theta_rad, weight=weight)
    return update


def goal_update_to_proto(update: GoalUpdate) -> robot_pb2.GoalUpdate:
    """One item of a goal's watch: a state, a numbered event or feedback."""
    if isinstance(update, NumberedEvent):
        return robot_pb2.GoalUpdate(event=event_to_proto(update.index, update.event))
    if isinstance(update, GoalFeedback):
        return robot_pb2.GoalUpdate(feedback=feedback_to_proto(update))
    return robot_pb2.GoalUpdate(state=goal_to_proto(update))


def track_run_to_proto(scene_name: str, state: TrackState | None) -> robot_pb2.TrackRun:
    """The run now; is_track false (and nothing else) in scenes without a track."""
    if state is None:
        return robot_pb2.TrackRun(is_track=False, scene_name=scene_name)
    return robot_pb2.TrackRun(
        is_track=True, scene_name=scene_name, phase=state.phase, attempt=state.attempt,
        elapsed_s=state.elapsed_s, errors=state.errors, last_attempt=state.last_attempt,
        last_total_time_s=state.last_total_time_s, last_errors=state.last_errors,
        last_finished_unix_s=state.last_finished_unix_s, started_unix_s=state.started_unix_s,
        last_started_unix_s=state.last_started_unix_s,
    )


def track_event_to_proto(event: TrackEvent) -> robot_pb2.TrackEvent:
    """One event of the run."""
    return robot_pb2.TrackEvent(
        index=event.index, kind=event.kind, sim_time_s=event.sim_time_s, unix_s=event.unix_s,
        attempt=event.attempt, elapsed_s=event.elapsed_s, errors=event.errors, message=event.message)


def health_to_proto(health: RobotHealth) -> robot_pb2.RobotHealth:
    loop, faults, process = health.loop, health.faults, health.process
    return robot_pb2.RobotHealth(
        real_time_factor=loop.real_time_factor, loop_lag_ms_p50=loop.lag_ms_p50, loop_lag_ms_max=loop.lag_ms_max,
        parked=loop.parked, cpu_percent=process.cpu_percent, rss_bytes=process.rss_bytes,
        uptime_s=process.uptime_s, version=process.version, pid=process.pid,
        faults=[robot_pb2.RobotFault(unix_s=f.unix_s, kind=f.kind, message=f.message) for f in faults],
        log_tail=process.log_tail, restartable=process.restartable, restarts=process.restarts)
