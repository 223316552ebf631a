"""The middleware's connection to one robot's skill server: deadlines, reconnect, streams, control."""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections.abc import AsyncGenerator, AsyncIterator, Iterator
from dataclasses import dataclass
from typing import Protocol, TypeVar

import grpc
from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.robots.fanout import FanoutHub
from middleware.robots.messages import pack_camera_frame, pack_localization, pack_telemetry
from middleware.robots.refusals import CommandRefused, RobotUnavailable
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

# gRPC reconnects a channel by itself; these bound how long a restarted robot stays unnoticed.
CHANNEL_OPTIONS = [
    ("grpc.initial_reconnect_backoff_ms", 200),
    ("grpc.min_reconnect_backoff_ms", 200),
    ("grpc.max_reconnect_backoff_ms", 3000),
    ("grpc.keepalive_time_ms", 10000),
    ("grpc.keepalive_timeout_ms", 5000),
]
POSES_HZ = 5.0  # the poses hub's rate: the class wall draws each robot five times a second

Message = TypeVar("Message", covariant=True)


class ServerStream(Iterator[Message], Protocol):
    """A gRPC server stream: iterating it yields the messages; cancel() ends it."""

    def cancel(self) -> bool:
        """Ends the stream (the iteration then raises grpc.RpcError CANCELLED)."""


@dataclass(frozen=True)
class DriveResult:
    """The skill server's answer to a drive command."""

    applied_sequence: int
    linear_mps: float
    angular_radps: float
    round_trip_ms: float  # middleware -> skill server -> middleware, the paper's second leg


def _json_to_parameter(value: object) -> robot_pb2.ParameterValue:
    if isinstance(value, bool):
        return robot_pb2.ParameterValue(bool_value=value)
    if isinstance(value, int):
        return robot_pb2.ParameterValue(int_value=value)
    if isinstance(value, float):
        return robot_pb2.ParameterValue(double_value=value)
    return robot_pb2.ParameterValue(string_value=str(value))


class RobotLink:
    """One channel to one robot, shared by every request and viewer of this process."""

    def __init__(self, name: str, address: str, rpc_timeout_s: float = 1.0) -> None:
        self.name = name
        self.address = address
        self.rpc_timeout_s = rpc_timeout_s
        self._channel = grpc.insecure_channel(address, options=CHANNEL_OPTIONS)
        self._stub = robot_pb2_grpc.RobotStub(self._channel)
        self._info: robot_pb2.RobotInfo | None = None
        self._info_at = 0.0
        self._closed = False
        # A grpc.aio channel for streams read on the channel loop (one asyncio loop per process), made there.
        self._aio: tuple[asyncio.AbstractEventLoop, grpc.aio.Channel, robot_pb2_grpc.RobotStub] | None = None
        self._sequence_lock = threading.Lock()
        self._highest_sequence = 0
        self.camera = FanoutHub(f"{name}-camera", self._open_camera, pack_camera_frame, _cancel_call)
        self.telemetry = FanoutHub(f"{name}-telemetry", self._open_telemetry, pack_telemetry, _cancel_call)
        self.localization = FanoutHub(f"{name}-localization", self._open_localization, pack_localization,
                                      _cancel_call)
        # The pose, speeds and battery alone, POSES_HZ times a second: for a viewer of many robots (the class wall)
        # where no console of this process pumps the robot's whole telemetry anyway.
        self.poses = FanoutHub(f"{name}-poses", self._open_poses, pack_telemetry, _cancel_call)
        self._skills: list[robot_pb2.SkillDescription] | None = None
        self._scene: robot_pb2.SceneDescription | None = None
        self._scene_at = 0.0
        self.unreachable_since: float | None = None  # monotonic time of the first failed call in a row

    def info(self, refresh: bool = False, max_age_s: float | None = None) -> robot_pb2.RobotInfo:
        """The robot's description (cached once fetched; asked again when refresh, or older than max_age_s)."""
        stale = max_age_s is not None and time.monotonic() - self._info_at > max_age_s
        if self._info is None or refresh or stale:
            self._info = self._call(self._stub.GetRobotInfo, robot_pb2.GetRobotInfoRequest())
            self._info_at = time.monotonic()
        return self._info

    def scene(self, max_age_s: float) -> robot_pb2.SceneDescription:
        """The robot's static world (GetScene), kept once fetched; older than max_age_s, the robot is asked again
        with the version held, and answers with the version alone while the world is the same."""
        scene = self._scene
        if scene is None or time.monotonic() - self._scene_at > max_age_s:
            held = scene.version if scene is not None else ""
            answer = self._call(self._stub.GetScene, robot_pb2.GetSceneRequest(known_version=held))
            if scene is None or not answer.unchanged:
                scene = self._scene = answer
            self._scene_at = time.monotonic()
        return scene

    def skills(self, refresh: bool = False) -> list[robot_pb2.SkillDescription]:
        """The skills the robot offers, with their parameter schemas (cached once fetched)."""
        if self._skills is None or refresh:
            self._skills = list(self._call(self._stub.ListSkills, robot_pb2.ListSkillsRequest()).skills)
        return self._skills

    def measure_round_trip_ms(self) -> float:
        """The duration of one small unary call to the skill server, in milliseconds."""
        started = time.perf_counter()
        self._call(self._stub.GetRobotInfo, robot_pb2.GetRobotInfoRequest())
        return (time.perf_counter() - started) * 1000

    def activate_skill(self, token: str, skill: str, parameters: dict[str, object],
                       preempt: bool) -> robot_pb2.GoalState:
        """Starts a skill as a goal under the controller's token."""
        request = robot_pb2.ActivateSkillRequest(
            token=token, skill=skill, preempt=preempt,
            parameters={name: _json_to_parameter(value) for name, value in parameters.items()},
        )
        return self._call(self._stub.ActivateSkill, request).goal

    def run_plan(self, token: str, name: str, plan: robot_pb2.PlanBlock, preempt: bool) -> robot_pb2.GoalState:
        """Starts a plan as one motor goal "plan:<name>" under the controller's token."""
        request = robot_pb2.RunPlanRequest(token=token, name=name, plan=plan, preempt=preempt)
        return self._call(self._stub.RunPlan, request).goal

    def cancel_goal(self, token: str, goal_id: str) -> robot_pb2.GoalState:
        """Cancels a goal; the answer says the error left."""
        return self._call(self._stub.CancelGoal, robot_pb2.CancelGoalRequest(token=token, goal_id=goal_id),
                          not_found_code="unknown_goal")

    def clear_map(self, token: str) -> list[str]:
        """Forgets the robot's environment model; the ids of the mapping and localization goals that ended."""
        answer = self._call(self._stub.ClearMap, robot_pb2.ClearMapRequest(token=token))
        return list(answer.ended_goal_ids)

    def return_to_dock(self, token: str) -> robot_pb2.ReturnToDockResponse:
        """Carries the robot to its dock; the goals that ended and the dock's pose."""
        return self._call(self._stub.ReturnToDock, robot_pb2.ReturnToDockRequest(token=token))

    def health(self) -> robot_pb2.RobotHealth:
        """The robot's loop, process, faults and log tail (telediagnosis)."""
        return self._call(self._stub.GetHealth, robot_pb2.GetHealthRequest())

    def restart(self, token: str) -> robot_pb2.RestartResponse:
        """Restarts the robot's process (it answers first, then comes back on the same address)."""
        return self._call(self._stub.Restart, robot_pb2.RestartRequest(token=token))

    def place_robot(self, token: str, pose: robot_pb2.Pose2D, kidnap: bool = False) -> robot_pb2.PlaceRobotResponse:
        """Places the robot at pose (kidnap: without telling it); the goals that ended and the pose."""
        return self._call(self._stub.PlaceRobot, robot_pb2.PlaceRobotRequest(token=token, pose=pose, kidnap=kidnap))

    def odometry_pose(self) -> robot_pb2.Pose2D:
        """Where the robot's odometry says it stands now (what a run on it is measured in): the first message of a
        pose-only telemetry stream of its own, which is fresh whether or not anyone watches the robot.
        RobotUnavailable when it does not answer within the call deadline."""
        return self._first_telemetry(pose_only=True).odometry.pose

    def poses_now(self) -> tuple[robot_pb2.Pose2D, robot_pb2.Pose2D]:
        """(odometry, where the robot truly stands) now, from the first message of a telemetry stream of its own
        (the truth is for the middleware's own choices, such as where a copy of the robot starts; never forwarded
        to a student). RobotUnavailable when it does not answer within the call deadline."""
        telemetry = self._first_telemetry(pose_only=False)
        return telemetry.odometry.pose, telemetry.ground_truth

    def _first_telemetry(self, pose_only: bool) -> robot_pb2.Telemetry:
        stream = self._stub.StreamTelemetry(robot_pb2.StreamTelemetryRequest(pose_only=pose_only),
                                            timeout=self.rpc_timeout_s)
        try:
            return next(iter(stream))
        except grpc.RpcError as error:
            raise _translate(error) from None
        except StopIteration:
            raise RobotUnavailable(gettext("%(robot)s sent no telemetry.", robot=self.name)) from None
        finally:
            stream.cancel()

    def goals(self) -> list[robot_pb2.GoalState]:
        """The running goals and those kept after their end, oldest first."""
        return list(self._call(self._stub.ListGoals, robot_pb2.ListGoalsRequest()).goals)

    def get_goal(self, goal_id: str) -> robot_pb2.GoalState:
        """A running goal or one that ended recently."""
        return self._call(self._stub.GetGoal, robot_pb2.GetGoalRequest(goal_id=goal_id), not_found_code="unknown_goal")

    async def watch_goal(self, goal_id: str) -> AsyncGenerator[robot_pb2.GoalUpdate, None]:
        """The goal's updates until it ends, read on the running asyncio loop without a thread of its own (a stream
        per watcher: goals have few); leaving the iteration cancels the stream. grpc.RpcError as the sync calls."""
        call = self._aio_stub().WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal_id, feedback_rate_hz=5))
        try:
            async for update in call:
                yield update
        finally:
            call.cancel()

    def _aio_stub(self) -> robot_pb2_grpc.RobotStub:
        loop = asyncio.get_running_loop()
        if self._aio is None or self._aio[0] is not loop:
            channel = grpc.aio.insecure_channel(self.address, options=CHANNEL_OPTIONS)
            self._aio = (loop, channel, robot_pb2_grpc.RobotStub(channel))
        return self._aio[2]

    async def watch_telemetry(self, rate_hz: float) -> AsyncGenerator[robot_pb2.Telemetry, None]:
        """A telemetry stream of its own, ground truth included (for graders; never forwarded to browsers), read on the
        running asyncio loop without a thread of its own; leaving the iteration cancels the stream."""
        call = self._aio_stub().StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=rate_hz))
        try:
            async for message in call:
                yield message
        finally:
            call.cancel()

    def stream_telemetry(self, rate_hz: float) -> ServerStream[robot_pb2.Telemetry]:
        """A telemetry stream of its own, ground truth included (for graders; never forwarded to browsers)."""
        return self._stub.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=rate_hz))

    def stream_poses(self, rate_hz: float) -> ServerStream[robot_pb2.Telemetry]:
        """A pose-only telemetry stream of its own (odometry and times), at rate_hz of the robot's sim time."""
        return self._stub.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=rate_hz, pose_only=True))

    def get_map(self) -> robot_pb2.OccupancyGrid:
        """The occupancy grid built so far."""
        return self._call(self._stub.GetMap, robot_pb2.GetMapRequest())

    def evidence_grid(self, sensor: robot_pb2.EvidenceSensor, part: robot_pb2.EvidencePart) -> robot_pb2.EvidenceGrid:
        """Teleperception's evidence grid (the chosen layers); reading it keeps it accumulating for 10 s."""
        return self._call(self._stub.GetEvidenceGrid, robot_pb2.GetEvidenceGridRequest(watch=True, sensor=sensor,
                                                                                      part=part))

    def reset_evidence_grid(self, token: str) -> robot_pb2.EvidenceGrid:
        """Forgets the evidence grid and the readings kept (supervisory); the emptied grid."""
        return self._call(self._stub.ResetEvidenceGrid, robot_pb2.ResetEvidenceGridRequest(token=token))

    def perception_readings(self, after_index: int = 0) -> robot_pb2.PerceptionReadings:
        """The raw readings the evidence grid integrated, numbered above after_index."""
        return self._call(self._stub.GetPerceptionReadings,
                          robot_pb2.GetPerceptionReadingsRequest(after_index=after_index))

    def track_run(self) -> robot_pb2.TrackRun:
        """The run on the robot's track now (phase, time, line contacts, last finished attempt); is_track false off a
        track."""
        return self._call(self._stub.GetTrackRun, robot_pb2.GetTrackRunRequest())

    def restart_track_run(self) -> robot_pb2.TrackRun:
        """Ends the attempt under way on the robot's track without a result (the next departure from A starts a
        new one); the run after that."""
        return self._call(self._stub.RestartTrackRun, robot_pb2.RestartTrackRunRequest())

    def pose_log(self, from_unix_s: float, to_unix_s: float) -> robot_pb2.PoseLog:
        """The robot's true and odometric poses between two wall-clock times, as the robot kept them (the run of an
        experimental attempt; ground truth, never for a student's page)."""
        return self._call(self._stub.GetPoseLog, robot_pb2.GetPoseLogRequest(from_unix_s=from_unix_s,
                                                                             to_unix_s=to_unix_s))

    def is_online(self) -> bool:
        """Whether the skill server answers now."""
        try:
            self.info(refresh=True)
        except RobotUnavailable:
            return False
        return True

    def reserve_sequences(self) -> int:
        """A base above every sequence sent so far, by this process or any other: a new driver numbers its
        commands base+1, base+2... The robot ignores a sequence not above the last one of the same token, and a
        console reconnected to another worker keeps its token, so the base is the wall clock in milliseconds
        (shared by every process and host), which outruns any console's numbering (at most 50 commands a second)."""
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, time.time_ns() // 1_000_000)
            return self._highest_sequence

    def next_sequence(self) -> int:
        """A sequence number above every one this process sent or saw acknowledged, for a single command (a stop,
        a cue)."""
        with self._sequence_lock:
            self._highest_sequence += 1
            return self._highest_sequence

    def set_controller(self, token: str) -> None:
        """Tells the skill server whose commands to obey; an empty token revokes control and stops the base."""
        self._call(self._stub.SetController, robot_pb2.SetControllerRequest(token=token))

    def drive(self, token: str, sequence: int, linear_mps: float, angular_radps: float) -> DriveResult:
        """Sends a drive command under the controller's token; the skill server refuses any other token."""
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, sequence)
        command = robot_pb2.DriveCommand(
            token=token, sequence=sequence, linear_mps=linear_mps, angular_radps=angular_radps
        )
        started = time.perf_counter()
        ack = self._call(self._stub.Drive, command)
        round_trip_ms = (time.perf_counter() - started) * 1000
        with self._sequence_lock:  # a newer sequence in force was sent by another process: number above it
            self._highest_sequence = max(self._highest_sequence, ack.applied_sequence)
        return DriveResult(ack.applied_sequence, ack.linear_mps, ack.angular_radps, round_trip_ms)

    async def drive_async(self, token: str, sequence: int, linear_mps: float, angular_radps: float) -> DriveResult:
        """drive() on the running asyncio loop (grpc.aio): no thread waits for the robot, however slow it is."""
        if self._closed:
            raise RobotUnavailable(gettext("The link to %(robot)s is closed.", robot=self.name))
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, sequence)
        command = robot_pb2.DriveCommand(
            token=token, sequence=sequence, linear_mps=linear_mps, angular_radps=angular_radps
        )
        started = time.perf_counter()
        try:
            ack = await self._aio_stub().Drive(command, timeout=self.rpc_timeout_s)
        except grpc.RpcError as error:  # grpc.aio.AioRpcError is one
            translated = _translate(error)
            if isinstance(translated, RobotUnavailable) and self.unreachable_since is None:
                self.unreachable_since = time.monotonic()
            raise translated from None
        self.unreachable_since = None
        round_trip_ms = (time.perf_counter() - started) * 1000
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, ack.applied_sequence)
        return DriveResult(ack.applied_sequence, ack.linear_mps, ack.angular_radps, round_trip_ms)

    def open_drive_call(self) -> grpc.aio.StreamStreamCall:
        """A DriveStream call on the running loop (grpc.aio), for one driver's commands: drive_stream.DriveStream
        writes them and reads the answers; RobotUnavailable once the link is closed."""
        if self._closed:
            raise RobotUnavailable(gettext("The link to %(robot)s is closed.", robot=self.name))
        return self._aio_stub().DriveStream()

    def note_drive_sent(self, sequence: int) -> None:
        """A drive command numbered sequence is on its way (a later single command is numbered above it)."""
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, sequence)

    def note_drive_answer(self, applied_sequence: int) -> None:
        """The robot answered a drive command: it is reachable, and a newer sequence in force (sent by another
        process) is numbered above."""
        self.unreachable_since = None
        with self._sequence_lock:
            self._highest_sequence = max(self._highest_sequence, applied_sequence)

    def note_unreachable(self) -> None:
        """A call to the robot failed as unreachable (the first of a row starts the count)."""
        if self.unreachable_since is None:
            self.unreachable_since = time.monotonic()

    def get_limits(self) -> robot_pb2.Limits:
        """The velocity ceilings and the deadman (watchdog) timeout in force, with the ranges the robot accepts."""
        return self._call(self._stub.GetLimits, robot_pb2.GetLimitsRequest())

    def set_limits(self, token: str, max_linear_mps: float, max_angular_radps: float,
                   watchdog_s: float) -> robot_pb2.Limits:
        """Changes the limits under the controller's token (0 keeps a value); the limits in force afterwards."""
        return self._call(self._stub.SetLimits, robot_pb2.SetLimitsRequest(
            token=token, max_linear_mps=max_linear_mps, max_angular_radps=max_angular_radps, watchdog_s=watchdog_s))

    def close(self) -> None:
        """Stops the streams and closes the channel."""
        self.camera.close()
        self.telemetry.close()
        self.localization.close()
        self.poses.close()
        self._closed = True
        self._channel.close()
        if self._aio is not None:
            loop, channel, _ = self._aio
            self._aio = None
            with contextlib.suppress(RuntimeError):  # its loop has already stopped: nothing is left to close
                asyncio.run_coroutine_threadsafe(channel.close(), loop)

    # The hubs' upstreams: grpc.aio calls on the channel loop (the hub's pump calls these there).
    def _open_camera(self) -> AsyncIterator[object]:
        return self._aio_stub().StreamCamera(robot_pb2.StreamCameraRequest(max_fps=15))

    def _open_localization(self) -> AsyncIterator[object]:
        return self._aio_stub().StreamLocalization(robot_pb2.StreamLocalizationRequest(rate_hz=5, max_particles=200))

    def _open_telemetry(self) -> AsyncIterator[object]:
        return self._aio_stub().StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=10))

    def _open_poses(self) -> AsyncIterator[object]:
        return self._aio_stub().StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=POSES_HZ, pose_only=True))

    def _call(self, method, request, not_found_code: str = "unknown_skill"):
        try:
            reply = method(request, timeout=self.rpc_timeout_s)
        except grpc.RpcError as error:
            translated = _translate(error, not_found_code)
            if isinstance(translated, RobotUnavailable) and self.unreachable_since is None:
                self.unreachable_since = time.monotonic()
            raise translated from None
        except ValueError:
            if not self._closed:
                raise
            # A handler still running while the app shuts down, such as a driver's parting stop.
            raise RobotUnavailable(gettext("The link to %(robot)s is closed.", robot=self.name)) from None
        self.unreachable_since = None
        return reply


_REFUSAL_CODES = {
    grpc.StatusCode.NOT_FOUND: "not_found",
    grpc.StatusCode.INVALID_ARGUMENT: "invalid_field",
    grpc.StatusCode.PERMISSION_DENIED: "not_controller",
    grpc.StatusCode.UNAUTHENTICATED: "unauthenticated",
    grpc.StatusCode.FAILED_PRECONDITION: "not_possible_now",
}


def answers_at(name: str, address: str, rpc_timeout_s: float = 1.0) -> bool:
    """Whether a skill server answers at address now (a robot run by another process, or by nobody)."""
    link = RobotLink(name, address, rpc_timeout_s)
    try:
        return link.is_online()
    finally:
        link.close()


def _translate(error: grpc.RpcError, not_found_code: str = "unknown_skill") -> CommandRefused | RobotUnavailable:
    code = error.code()
    field = None
    if code == grpc.StatusCode.INVALID_ARGUMENT:
        field = dict(error.trailing_metadata() or ()).get("field")
    return translate_status(code, error.details() or "", field, not_found_code)


def translate_status(code: grpc.StatusCode, details: str, field: str | None = None,
                     not_found_code: str = "unknown_skill") -> CommandRefused | RobotUnavailable:
    """A robot's status (a call's, or a refusal a drive stream answered with) as the middleware's refusal: the one
    map from status codes to refusal codes."""
    if code in _REFUSAL_CODES:
        named = (field or details.split(" ", 1)[0]) if code == grpc.StatusCode.INVALID_ARGUMENT else None
        return CommandRefused(_REFUSAL_CODES[code], details, named, not_found_code)
    if code == grpc.StatusCode.DEADLINE_EXCEEDED:
        return RobotUnavailable(gettext("The robot did not answer in time."))
    return RobotUnavailable(gettext("The robot is not reachable right now."))


def _cancel_call(stream: AsyncIterator[object]) -> None:
    cancel = getattr(stream, "cancel", None)
    if cancel is not None:
        cancel()
