"""The one gRPC adapter: translates proto <-> domain and maps domain errors to status codes."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import grpc

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.errors import InvalidParameter, MissingControllerToken, NotController, WorldStopped
from skill_server.sequencer import Sequencer
from skill_server.service import convert
from skill_server.service.common import SimTimePacer, abort, stream_rate
from skill_server.service.course_rpcs import CourseRpcs
from skill_server.service.goal_rpcs import GoalRpcs
from skill_server.sim.camera import DEFAULT_CAMERA_FPS, MAX_CAMERA_FPS
from skill_server.sim.world import World
from skill_server.skills.registry import SkillRegistry

DEFAULT_TELEMETRY_HZ = 10.0
MAX_TELEMETRY_HZ = 50.0
STREAM_POLL_S = 0.25  # how long a stream waits before re-checking that its client is still there



class RobotService(GoalRpcs, CourseRpcs, robot_pb2_grpc.RobotServicer):
    """telelab.v1.Robot over one World and its Sequencer; holds no robot state of its own."""

    def __init__(self, world: World, skills: SkillRegistry, robot_name: str, sequencer: Sequencer) -> None:
        self._world = world
        self._skills = skills
        self._robot_name = robot_name
        self._laser = world.describe().laser
        self._sequencer = sequencer

    def GetRobotInfo(
        self, request: robot_pb2.GetRobotInfoRequest, context: grpc.ServicerContext
    ) -> robot_pb2.RobotInfo:
        """Describes the robot, its sensors and its scene."""
        info = self._world.describe()
        spec = info.spec
        return robot_pb2.RobotInfo(
            robot_name=self._robot_name,
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
        )

    def ListSkills(
        self, request: robot_pb2.ListSkillsRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ListSkillsResponse:
        """Lists the skills with the schema of their parameters."""
        return robot_pb2.ListSkillsResponse(skills=[convert.skill_to_proto(s) for s in self._skills.descriptions()])

    def SetController(
        self, request: robot_pb2.SetControllerRequest, context: grpc.ServicerContext
    ) -> robot_pb2.SetControllerResponse:
        """Names the controller; an empty token revokes control and stops the base."""
        self._world.set_controller(request.token)
        return robot_pb2.SetControllerResponse()

    def Drive(self, request: robot_pb2.DriveCommand, context: grpc.ServicerContext) -> robot_pb2.DriveAck:
        """Sets the wheel velocities if the token is the controller's."""
        try:
            ack = self._world.drive(request.token, request.sequence, request.linear_mps, request.angular_radps)
        except MissingControllerToken as error:
            abort(context, grpc.StatusCode.UNAUTHENTICATED, str(error))
        except NotController:
            abort(
                context,
                grpc.StatusCode.PERMISSION_DENIED,
                "this command's controller token is not the robot's current controller",
            )
        except InvalidParameter as error:
            abort(context, grpc.StatusCode.INVALID_ARGUMENT, error.message)
        if self._sequencer.motor_goal_running:
            # The teleoperator takes the wheels back: end the motor goal before answering, so a stop that
            # was acknowledged has also ended the goal (the loop runs queued commands between ticks).
            self._world.run_in_loop(lambda: self._sequencer.on_direct_drive(self._world.drive_version))
        return robot_pb2.DriveAck(
            applied_sequence=ack.applied_sequence, linear_mps=ack.linear_mps, angular_radps=ack.angular_radps
        )

    def StreamTelemetry(
        self, request: robot_pb2.StreamTelemetryRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.Telemetry]:
        """Odometry, ground truth, sonar and laser at the requested rate of sim time."""
        rate_hz = stream_rate(context, "rate_hz", request.rate_hz, DEFAULT_TELEMETRY_HZ, MAX_TELEMETRY_HZ, "Hz")
        cancelled = self._cancellation(context)
        pacer = SimTimePacer(1.0 / rate_hz)
        last_tick = -1
        while context.is_active() and not cancelled.is_set():
            snapshot = self._world.wait_for_snapshot(last_tick, STREAM_POLL_S, cancelled)
            if snapshot is None:
                if not self._world.is_running:
                    return
                continue
            last_tick = snapshot.tick
            if pacer.due(snapshot.sim_time_s):
                yield convert.telemetry_to_proto(snapshot, self._laser)

    def StreamCamera(
        self, request: robot_pb2.StreamCameraRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.CameraFrame]:
        """JPEG frames, rendered only while someone watches and encoded once for all viewers."""
        max_fps = stream_rate(context, "max_fps", request.max_fps, DEFAULT_CAMERA_FPS, MAX_CAMERA_FPS, "fps")
        cancelled = self._cancellation(context)
        pacer = SimTimePacer(1.0 / max_fps)
        last_sequence = 0
        try:
            subscription = self._world.subscribe_camera(max_fps)
        except WorldStopped:
            return
        with subscription:
            while context.is_active() and not cancelled.is_set():
                frame = self._world.wait_for_frame(last_sequence, STREAM_POLL_S, cancelled)
                if frame is None:
                    if not self._world.is_running:
                        return
                    continue
                last_sequence = frame.frame_sequence
                if pacer.due(frame.sim_time_s):
                    yield convert.frame_to_proto(frame)

    def _cancellation(self, context: grpc.ServicerContext) -> threading.Event:
        cancelled = threading.Event()

        def on_rpc_done() -> None:
            cancelled.set()
            self._world.wake_waiters()

        context.add_callback(on_rpc_done)
        return cancelled
