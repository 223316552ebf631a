"""Many stand-in robots in one process, for measuring the web tier with as many robots as a class has: each is a
grpc.aio server on a port of its own speaking `telelab.v1.Robot` as a skill server does for a console (its
description, the controller token, drive commands, telemetry at 10 Hz with sonar and laser, localization at 5 Hz,
camera frames at the asked rate), moved by the commands it obeys with unicycle kinematics and stopped by its deadman.
No pybullet: a real skill server costs about 0.06 of a core (benchmarks/farm.py), so 200 of them would measure the
robots, not the web tier. Every other call answers UNIMPLEMENTED.

Run alone: `python -m benchmarks.standin_robots N` prints one `name=127.0.0.1:port` line per robot, then serves
until stdin closes.
"""

from __future__ import annotations

import asyncio
import math
import sys
import threading
import time
from collections.abc import AsyncIterator

import grpc
import numpy
import simplejpeg

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

TELEMETRY_HZ = 10.0
LOCALIZATION_HZ = 5.0
DEADMAN_S = 0.5
LASER_BEAMS = 181  # what the lab robot's laser sends
SONARS = 16
# A grey 320x240 JPEG, encoded once (about 3 kB): the camera's bytes are the web tier's to relay, not to render.
GREY_JPEG = simplejpeg.encode_jpeg(numpy.full((240, 320, 3), 128, numpy.uint8), quality=70)


class StandInRobot(robot_pb2_grpc.RobotServicer):
    """One robot's state and answers."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.token = ""
        self.applied_sequence = 0
        self.linear_mps = self.angular_radps = 0.0
        self.commanded_at = 0.0
        self.x_m = self.y_m = self.theta_rad = 0.0
        self.moved_at = time.monotonic()
        self.started = time.monotonic()
        self.drives = 0  # commands applied
        self.drive_calls = 0  # unary Drive calls
        self.drive_streams = 0  # DriveStream calls opened

    def _advance(self) -> None:
        now = time.monotonic()
        if now - self.commanded_at > DEADMAN_S:
            self.linear_mps = self.angular_radps = 0.0
        dt_s = now - self.moved_at
        self.moved_at = now
        self.x_m += self.linear_mps * math.cos(self.theta_rad) * dt_s
        self.y_m += self.linear_mps * math.sin(self.theta_rad) * dt_s
        self.theta_rad = math.remainder(self.theta_rad + self.angular_radps * dt_s, math.tau)

    def _pose(self) -> robot_pb2.Pose2D:
        return robot_pb2.Pose2D(x_m=self.x_m, y_m=self.y_m, theta_rad=self.theta_rad)

    async def GetRobotInfo(self, request, context):  # noqa: N802 - gRPC's method names
        return robot_pb2.RobotInfo(robot_name=self.name, scene_name="stand-in", wheel_base_m=0.3,
                                   wheel_radius_m=0.05, body_radius_m=0.2, max_linear_mps=0.5,
                                   max_angular_radps=1.5, deadman_timeout_s=DEADMAN_S, camera_hfov_deg=60.0,
                                   camera_width_px=320, camera_height_px=240)

    async def SetController(self, request, context):  # noqa: N802
        self.token = request.token
        if not request.token:
            self.linear_mps = self.angular_radps = 0.0
        return robot_pb2.SetControllerResponse()

    async def GetLimits(self, request, context):  # noqa: N802
        return robot_pb2.Limits(max_linear_mps=0.5, max_angular_radps=1.5, watchdog_s=DEADMAN_S)

    def _apply_drive(self, request: robot_pb2.DriveCommand) -> robot_pb2.DriveStreamAck:
        """Drive's rule: the controller's token only, a sequence above the last in force, the velocities clamped."""
        if not request.token or request.token != self.token:
            return robot_pb2.DriveStreamAck(sequence=request.sequence, refusal=robot_pb2.CommandRefusal(
                status_code=grpc.StatusCode.PERMISSION_DENIED.value[0], message="not the controller's token"))
        self._advance()
        if request.sequence > self.applied_sequence:
            self.applied_sequence = request.sequence
            self.linear_mps = max(-0.5, min(0.5, request.linear_mps))
            self.angular_radps = max(-1.5, min(1.5, request.angular_radps))
            self.commanded_at = time.monotonic()
            self.drives += 1
        return robot_pb2.DriveStreamAck(sequence=request.sequence, ack=robot_pb2.DriveAck(
            applied_sequence=self.applied_sequence, linear_mps=self.linear_mps, angular_radps=self.angular_radps))

    async def answer_drive(self, request: robot_pb2.DriveCommand) -> robot_pb2.DriveStreamAck:
        """One drive command's answer, for Drive and DriveStream alike (a test's slow robot waits here)."""
        return self._apply_drive(request)

    async def Drive(self, request, context):  # noqa: N802
        self.drive_calls += 1
        answer = await self.answer_drive(request)
        if answer.WhichOneof("outcome") == "refusal":
            await context.abort(grpc.StatusCode.PERMISSION_DENIED, answer.refusal.message)  # its only refusal
        return answer.ack

    async def DriveStream(self, request_iterator, context) -> AsyncIterator[robot_pb2.DriveStreamAck]:  # noqa: N802
        self.drive_streams += 1
        async for command in request_iterator:
            yield await self.answer_drive(command)

    async def StreamTelemetry(self, request, context) -> AsyncIterator[robot_pb2.Telemetry]:  # noqa: N802
        period_s = 1.0 / (request.rate_hz or TELEMETRY_HZ)
        tick = 0
        while True:
            self._advance()
            tick += 1
            pose = self._pose()
            message = robot_pb2.Telemetry(
                tick=tick, sim_time_s=time.monotonic() - self.started, capture_unix_s=time.time(),
                last_applied_sequence=self.applied_sequence,
                odometry=robot_pb2.Odometry(pose=pose, linear_mps=self.linear_mps, angular_radps=self.angular_radps),
                battery=robot_pb2.Battery(charge=0.9))
            if not request.pose_only:
                message.ground_truth.CopyFrom(pose)
                message.sonar.ranges_m.extend([3.0] * SONARS)
                message.laser.angle_min_rad = -math.pi / 2
                message.laser.angle_increment_rad = math.pi / (LASER_BEAMS - 1)
                message.laser.ranges_m.extend([4.0 + 0.001 * (tick % 7)] * LASER_BEAMS)
            yield message
            await asyncio.sleep(period_s)

    async def StreamLocalization(self, request, context) -> AsyncIterator[robot_pb2.LocalizationUpdate]:  # noqa: N802
        period_s = 1.0 / min(20.0, request.rate_hz or LOCALIZATION_HZ)
        while True:
            self._advance()
            pose = self._pose()
            yield robot_pb2.LocalizationUpdate(sim_time_s=time.monotonic() - self.started, active=False,
                                               odometry=pose, ground_truth=pose)
            await asyncio.sleep(period_s)

    async def StreamCamera(self, request, context) -> AsyncIterator[robot_pb2.CameraFrame]:  # noqa: N802
        period_s = 1.0 / (request.max_fps or 15.0)
        sequence = 0
        while True:
            self._advance()
            sequence += 1
            yield robot_pb2.CameraFrame(frame_sequence=sequence, capture_unix_s=time.time(),
                                        sim_time_s=time.monotonic() - self.started,
                                        last_applied_sequence=self.applied_sequence, pose_at_capture=self._pose(),
                                        width_px=320, height_px=240, jpeg=GREY_JPEG)
            await asyncio.sleep(period_s)


async def _unimplemented(self: StandInRobot, request: object, context: grpc.aio.ServicerContext) -> None:
    await context.abort(grpc.StatusCode.UNIMPLEMENTED, "a stand-in robot answers a console's calls only")


for _name, _method in vars(robot_pb2_grpc.RobotServicer).items():  # every other call: UNIMPLEMENTED, quietly
    if callable(_method) and not _name.startswith("_") and _name not in vars(StandInRobot):
        setattr(StandInRobot, _name, _unimplemented)


class StandInFleet:
    """count stand-in robots named prefix1..prefixN on one asyncio loop (a thread of this process)."""

    def __init__(self, count: int, prefix: str = "standin-") -> None:
        self.robots = [StandInRobot(f"{prefix}{i + 1}") for i in range(count)]
        self.addresses: dict[str, str] = {}
        self._servers: list[grpc.aio.Server] = []
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="standin-robots", daemon=True)
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self._start(), self._loop).result(60)

    async def _start(self) -> None:
        for robot in self.robots:
            server = grpc.aio.server()
            robot_pb2_grpc.add_RobotServicer_to_server(robot, server)
            port = server.add_insecure_port("127.0.0.1:0")
            await server.start()
            self._servers.append(server)
            self.addresses[robot.name] = f"127.0.0.1:{port}"

    @property
    def robots_setting(self) -> str:
        """The fleet as TELELAB_ROBOTS."""
        return ",".join(f"{name}={address}" for name, address in self.addresses.items())

    def stop(self) -> None:
        async def stop_all() -> None:
            await asyncio.gather(*(server.stop(0) for server in self._servers))

        asyncio.run_coroutine_threadsafe(stop_all(), self._loop).result(30)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)
        if not self._thread.is_alive():
            self._loop.close()  # its self-pipe sockets, else left to the garbage collector (ResourceWarning)


def main() -> None:
    fleet = StandInFleet(int(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 else "standin-")
    for name, address in fleet.addresses.items():
        print(f"{name}={address}", flush=True)
    sys.stdin.read()  # serve until the parent closes our stdin
    fleet.stop()


if __name__ == "__main__":
    main()
