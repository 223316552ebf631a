"""The Robot servicer: each RPC converts its request, calls the Robot facade and converts the answer.

Domain errors become status codes in one place, STATUS_OF_ERROR; a stream ends when its RPC ends (the
callback sets the stream's stopped event), the shape of grpc's examples/python/cancellation.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from typing import Any, Literal, TypeVar

import grpc

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.errors import (
    BatteryEmpty,
    InvalidParameter,
    MissingControllerToken,
    NoMap,
    NotController,
    NoTrack,
    NotRestartable,
    ResourceBusy,
    UnknownGoal,
    UnknownSkill,
    WorldStopped,
)
from skill_server.robot import DEFAULT_CAMERA_FPS, MAX_CAMERA_FPS, DriveOrder, DriveOutcome, Robot
from skill_server.service import convert, perception_convert
from skill_server.service.plan_convert import plan_from_proto

DEFAULT_TELEMETRY_HZ, MAX_TELEMETRY_HZ = 10.0, 50.0
DEFAULT_FEEDBACK_HZ, MAX_FEEDBACK_HZ = 10.0, 50.0
DEFAULT_LOCALIZATION_HZ, MAX_LOCALIZATION_HZ = 5.0, 20.0
MAX_STREAMED_PARTICLES = 2000

# The one table from the robot core's errors to status codes; the status message is the error's sentence.
STATUS_OF_ERROR: list[tuple[type[Exception], grpc.StatusCode]] = [
    (UnknownSkill, grpc.StatusCode.NOT_FOUND),
    (UnknownGoal, grpc.StatusCode.NOT_FOUND),
    (InvalidParameter, grpc.StatusCode.INVALID_ARGUMENT),  # the field also goes as trailing metadata "field"
    (ResourceBusy, grpc.StatusCode.FAILED_PRECONDITION),
    (NoMap, grpc.StatusCode.FAILED_PRECONDITION),
    (NoTrack, grpc.StatusCode.FAILED_PRECONDITION),
    (BatteryEmpty, grpc.StatusCode.FAILED_PRECONDITION),
    (NotRestartable, grpc.StatusCode.FAILED_PRECONDITION),
    (MissingControllerToken, grpc.StatusCode.UNAUTHENTICATED),
    (NotController, grpc.StatusCode.PERMISSION_DENIED),
    (WorldStopped, grpc.StatusCode.UNAVAILABLE),
]

T = TypeVar("T")
P = TypeVar("P")


class RobotService(robot_pb2_grpc.RobotServicer):
    """telelab.v1.Robot over one Robot; holds no robot state of its own."""

    def __init__(self, robot: Robot) -> None:
        self._robot = robot
        self._laser = robot.describe().laser

    # ---- the robot and its commands ----------------------------------------------------------------

    def GetRobotInfo(
        self, request: robot_pb2.GetRobotInfoRequest, context: grpc.ServicerContext
    ) -> robot_pb2.RobotInfo:
        """Describes the robot, its sensors and its scene."""
        return convert.robot_info_to_proto(self._robot.name, self._robot.describe())

    def GetScene(self, request: robot_pb2.GetSceneRequest,
                 context: grpc.ServicerContext) -> robot_pb2.SceneDescription:
        """The static world for views drawn elsewhere; only the version when the caller already holds it."""
        return convert.scene_to_proto(self._robot.scene_description(), request.known_version)

    def ListSkills(
        self, request: robot_pb2.ListSkillsRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ListSkillsResponse:
        """Lists the skills with the schema of their parameters."""
        return robot_pb2.ListSkillsResponse(skills=[convert.skill_to_proto(s) for s in self._robot.skills()])

    def SetController(
        self, request: robot_pb2.SetControllerRequest, context: grpc.ServicerContext
    ) -> robot_pb2.SetControllerResponse:
        """Names the controller; an empty token revokes control and stops the base."""
        with domain_errors(context):
            self._robot.set_controller(request.token)
        return robot_pb2.SetControllerResponse()

    def Drive(self, request: robot_pb2.DriveCommand, context: grpc.ServicerContext) -> robot_pb2.DriveAck:
        """Sets the wheel velocities if the token is the controller's (a running motor goal is preempted)."""
        with domain_errors(context):
            ack = self._robot.drive(request.token, request.sequence, request.linear_mps, request.angular_radps)
        return convert.drive_ack_to_proto(ack)

    def DriveStream(self, request_iterator: Iterator[robot_pb2.DriveCommand],
                    context: grpc.ServicerContext) -> Iterator[robot_pb2.DriveStreamAck]:
        """Drive for one driver's commands on one call: each answered in order, a refused one by its status code and
        sentence (the call goes on); the call ends UNAVAILABLE when the world stops."""
        orders = (DriveOrder(c.token, c.sequence, c.linear_mps, c.angular_radps) for c in request_iterator)
        with domain_errors(context):
            for outcome in self._robot.drive_each(orders):
                yield _drive_answer(outcome)

    def SetLimits(self, request: robot_pb2.SetLimitsRequest, context: grpc.ServicerContext) -> robot_pb2.Limits:
        """The controller's velocity ceilings and deadman timeout (0 keeps a value); INVALID_ARGUMENT names the
        field out of range or not finite, and nothing changes then."""
        with domain_errors(context):
            limits = self._robot.set_limits(request.token, request.max_linear_mps, request.max_angular_radps,
                                            request.watchdog_s)
        return convert.limits_to_proto(limits)

    def GetLimits(self, request: robot_pb2.GetLimitsRequest, context: grpc.ServicerContext) -> robot_pb2.Limits:
        """The limits in force and the ranges SetLimits accepts."""
        return convert.limits_to_proto(self._robot.limits())

    def ActivateSkill(
        self, request: robot_pb2.ActivateSkillRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ActivateSkillResponse:
        """Starts a skill as a goal, or refuses with a status code and a reason."""
        with domain_errors(context):
            parameters = convert.parameters_from_proto(request.parameters)
            activation = self._robot.activate(request.token, request.skill, parameters, request.preempt)
        return robot_pb2.ActivateSkillResponse(
            goal=convert.goal_to_proto(activation.goal), preempted_goal_id=activation.preempted_goal_id
        )

    def RunPlan(self, request: robot_pb2.RunPlanRequest,
                context: grpc.ServicerContext) -> robot_pb2.ActivateSkillResponse:
        """Runs a plan as one motor goal, or refuses: INVALID_ARGUMENT naming every fault's line, column and field
        (nothing moves then), else as ActivateSkill."""
        with domain_errors(context):
            activation = self._robot.run_plan(request.token, plan_from_proto(request), request.preempt)
        return robot_pb2.ActivateSkillResponse(
            goal=convert.goal_to_proto(activation.goal), preempted_goal_id=activation.preempted_goal_id
        )

    def CancelGoal(self, request: robot_pb2.CancelGoalRequest, context: grpc.ServicerContext) -> robot_pb2.GoalState:
        """Cancels a goal; answers its state afterwards."""
        with domain_errors(context):
            return convert.goal_to_proto(self._robot.cancel(request.token, request.goal_id))

    def GetGoal(self, request: robot_pb2.GetGoalRequest, context: grpc.ServicerContext) -> robot_pb2.GoalState:
        """The state of one goal."""
        with domain_errors(context):
            return convert.goal_to_proto(self._robot.goal(request.goal_id))

    def ListGoals(
        self, request: robot_pb2.ListGoalsRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ListGoalsResponse:
        """Running goals and the ones kept after their end."""
        return robot_pb2.ListGoalsResponse(goals=[convert.goal_to_proto(goal) for goal in self._robot.goals()])

    def GetMap(self, request: robot_pb2.GetMapRequest, context: grpc.ServicerContext) -> robot_pb2.OccupancyGrid:
        """The latest environment model; FAILED_PRECONDITION before any mapping."""
        with domain_errors(context):
            return convert.grid_to_proto(self._robot.environment_map())

    def ClearMap(self, request: robot_pb2.ClearMapRequest,
                 context: grpc.ServicerContext) -> robot_pb2.ClearMapResponse:
        """Forgets the environment model (supervisory); the goals built on it end."""
        with domain_errors(context):
            return robot_pb2.ClearMapResponse(ended_goal_ids=self._robot.clear_map(request.token))

    def ReturnToDock(self, request: robot_pb2.ReturnToDockRequest,
                     context: grpc.ServicerContext) -> robot_pb2.ReturnToDockResponse:
        """Carries the robot to its dock (supervisory); every goal ends, odometry restarts there."""
        with domain_errors(context):
            ended, dock = self._robot.return_to_dock(request.token)
            return robot_pb2.ReturnToDockResponse(ended_goal_ids=ended, dock=convert.pose_to_proto(dock))

    def GetHealth(self, request: robot_pb2.GetHealthRequest,
                  context: grpc.ServicerContext) -> robot_pb2.RobotHealth:
        """The loop against real time, the process, the faults and the log's last lines (telediagnosis)."""
        return convert.health_to_proto(self._robot.health())

    def Restart(self, request: robot_pb2.RestartRequest,
                context: grpc.ServicerContext) -> robot_pb2.RestartResponse:
        """Restarts the robot's process after answering (supervisory: the controller's token)."""
        with domain_errors(context):
            self._robot.restart(request.token)
            return robot_pb2.RestartResponse(restarting=True, message=(
                f"{self._robot.name} is restarting; it answers again in a few seconds, back at its dock."))

    def PlaceRobot(self, request: robot_pb2.PlaceRobotRequest,
                   context: grpc.ServicerContext) -> robot_pb2.PlaceRobotResponse:
        """Places the robot at a pose clear of walls and obstacles (supervisory); every goal ends, odometry restarts
        there. INVALID_ARGUMENT names the field at fault."""
        with domain_errors(context):
            pose = convert.pose_from_proto(request.pose)
            ended = self._robot.place(request.token, pose, kidnap=request.kidnap)
            return robot_pb2.PlaceRobotResponse(ended_goal_ids=ended, pose=convert.pose_to_proto(pose))

    def GetTrackRun(self, request: robot_pb2.GetTrackRunRequest,
                    context: grpc.ServicerContext) -> robot_pb2.TrackRun:
        """The track run now; is_track is false in scenes without a track."""
        return convert.track_run_to_proto(self._robot.scene_name, self._robot.track_run())

    def RestartTrackRun(self, request: robot_pb2.RestartTrackRunRequest,
                        context: grpc.ServicerContext) -> robot_pb2.TrackRun:
        """Ends the attempt under way without a result; the run after that (is_track false off a track)."""
        with domain_errors(context):
            return convert.track_run_to_proto(self._robot.scene_name, self._robot.restart_track_run())

    def GetPoseLog(self, request: robot_pb2.GetPoseLogRequest, context: grpc.ServicerContext) -> robot_pb2.PoseLog:
        """The poses kept between two wall-clock times; INVALID_ARGUMENT names the field at fault."""
        with domain_errors(context):
            samples, oldest = self._robot.pose_log(request.from_unix_s, request.to_unix_s)
        return robot_pb2.PoseLog(samples=[robot_pb2.PoseSample(
            unix_s=s[0], ground_truth=robot_pb2.Pose2D(x_m=s[1], y_m=s[2], theta_rad=s[3]),
            odometry=robot_pb2.Pose2D(x_m=s[4], y_m=s[5], theta_rad=s[6])) for s in samples],
            oldest_unix_s=oldest or 0.0)

    def GetEvidenceGrid(self, request: robot_pb2.GetEvidenceGridRequest,
                        context: grpc.ServicerContext) -> robot_pb2.EvidenceGrid:
        """Teleperception's evidence grid (the chosen layers); watch keeps it accumulating for 10 s more."""
        with domain_errors(context):
            sensors, parts = perception_convert.layers_from_proto(request)
            return perception_convert.evidence_to_proto(*self._robot.evidence(sensors, parts, request.watch))

    def ResetEvidenceGrid(self, request: robot_pb2.ResetEvidenceGridRequest,
                          context: grpc.ServicerContext) -> robot_pb2.EvidenceGrid:
        """Forgets the evidence grid and the readings kept (supervisory); the emptied grid."""
        with domain_errors(context):
            self._robot.reset_evidence(request.token)
            return perception_convert.evidence_to_proto(*self._robot.evidence(
                *perception_convert.layers_from_proto(robot_pb2.GetEvidenceGridRequest()), watch=False))

    def GetPerceptionReadings(self, request: robot_pb2.GetPerceptionReadingsRequest,
                              context: grpc.ServicerContext) -> robot_pb2.PerceptionReadings:
        """The raw readings kept, numbered above after_index."""
        return perception_convert.scans_to_proto(self._robot.perception_scans(request.after_index))

    # ---- streams -----------------------------------------------------------------------------------

    def StreamTelemetry(
        self, request: robot_pb2.StreamTelemetryRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.Telemetry]:
        """Odometry, ground truth, sonar and laser at the requested rate of sim time (pose_only: odometry only)."""
        return self._stream(context, lambda stopped: self._robot.telemetry(
            1.0 / convert.rate_from_proto("rate_hz", request.rate_hz, DEFAULT_TELEMETRY_HZ, MAX_TELEMETRY_HZ, "Hz"),
            stopped,
        ), lambda snapshot: convert.telemetry_to_proto(snapshot, self._laser, request.pose_only))

    def StreamCamera(
        self, request: robot_pb2.StreamCameraRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.CameraFrame]:
        """JPEG frames, rendered only while someone watches and encoded once for all viewers."""
        return self._stream(context, lambda stopped: self._robot.camera(
            convert.rate_from_proto("max_fps", request.max_fps, DEFAULT_CAMERA_FPS, MAX_CAMERA_FPS, "fps"), stopped
        ), convert.frame_to_proto)

    def WatchGoal(
        self, request: robot_pb2.WatchGoalRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.GoalUpdate]:
        """State, then events as they happen, every later state (executing, canceling, the final one) and
        feedback at the asked rate."""
        return self._stream(context, lambda stopped: self._robot.goal_updates(
            request.goal_id,
            1.0 / convert.rate_from_proto("feedback_rate_hz", request.feedback_rate_hz, DEFAULT_FEEDBACK_HZ,
                                          MAX_FEEDBACK_HZ, "Hz"),
            stopped,
        ), convert.goal_update_to_proto)

    def StreamLocalization(
        self, request: robot_pb2.StreamLocalizationRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.LocalizationUpdate]:
        """Estimate, uncertainty, particles, odometry and ground truth at the asked rate of sim time."""
        particles = min(int(request.max_particles), MAX_STREAMED_PARTICLES)
        return self._stream(context, lambda stopped: self._robot.localization(
            1.0 / convert.rate_from_proto("rate_hz", request.rate_hz, DEFAULT_LOCALIZATION_HZ, MAX_LOCALIZATION_HZ,
                                          "Hz"),
            stopped,
        ), lambda item: convert.localization_to_proto(*item, max_particles=particles))

    def StreamTrackEvents(self, request: robot_pb2.StreamTrackEventsRequest,
                          context: grpc.ServicerContext) -> Iterator[robot_pb2.TrackEvent]:
        """Every track event after request.after_index, until the client goes (FAILED_PRECONDITION off track)."""
        return self._stream(context, lambda stopped: self._robot.track_events(int(request.after_index), stopped),
                            convert.track_event_to_proto)

    def _stream(self, context: grpc.ServicerContext, open_stream: Callable[[threading.Event], Iterator[T]],
                to_proto: Callable[[T], P]) -> Iterator[P]:
        """Converts a domain stream item by item; it is told to stop (and woken) when the RPC ends."""
        stopped = threading.Event()

        def on_rpc_done() -> None:
            stopped.set()
            self._robot.wake_streams()

        if not context.add_callback(on_rpc_done):  # the RPC has already ended
            stopped.set()
        with domain_errors(context):
            for item in open_stream(stopped):
                yield to_proto(item)


def status_of(error: BaseException) -> grpc.StatusCode | None:
    """The status code STATUS_OF_ERROR gives a domain error (None: not one of the robot's refusals)."""
    return next((code for error_type, code in STATUS_OF_ERROR if isinstance(error, error_type)), None)


def _drive_answer(outcome: DriveOutcome) -> robot_pb2.DriveStreamAck:
    """One command's answer on a drive stream: its ack, or the status a unary Drive would have ended with."""
    if outcome.refusal is None and outcome.ack is not None:
        return robot_pb2.DriveStreamAck(sequence=outcome.sequence, ack=convert.drive_ack_to_proto(outcome.ack))
    refusal = outcome.refusal
    code = status_of(refusal) if refusal is not None else None
    return robot_pb2.DriveStreamAck(sequence=outcome.sequence, refusal=robot_pb2.CommandRefusal(
        status_code=(code or grpc.StatusCode.UNKNOWN).value[0], message=str(refusal),
        field=refusal.field if isinstance(refusal, InvalidParameter) else ""))


class domain_errors:  # noqa: N801 - used as a context manager, reads like a clause
    """Aborts the RPC with the status code STATUS_OF_ERROR gives a domain error, and the error's sentence."""

    def __init__(self, context: grpc.ServicerContext) -> None:
        self._context = context

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, traceback: Any) -> Literal[False]:
        if error is None:
            return False
        code = status_of(error)
        if code is not None:
            if isinstance(error, InvalidParameter):
                self._context.set_trailing_metadata((("field", error.field),))
            self._context.abort(code, str(error))
        return False
