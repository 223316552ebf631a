"""DriveStream: one driver's drive commands on one call, each answered in order by its sequence, under Drive's rule
(token, sequence, limits) and the deadman; a refused command is answered and the call goes on."""

from __future__ import annotations

import queue
from collections.abc import Iterator

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer

TOKEN = "stream-token"
DEADLINE_S = 10.0


class Driver:
    """A DriveStream call whose commands the test writes one at a time (the call stays open until close())."""

    def __init__(self, robot: robot_pb2_grpc.RobotStub) -> None:
        self._commands: queue.Queue[robot_pb2.DriveCommand | None] = queue.Queue()
        self._answers = robot.DriveStream(self._outgoing(), timeout=DEADLINE_S * 3)

    def _outgoing(self) -> Iterator[robot_pb2.DriveCommand]:
        while (command := self._commands.get()) is not None:
            yield command

    def send(self, token: str, sequence: int, linear_mps: float = 0.0, angular_radps: float = 0.0
             ) -> robot_pb2.DriveStreamAck:
        self._commands.put(robot_pb2.DriveCommand(token=token, sequence=sequence, linear_mps=linear_mps,
                                                  angular_radps=angular_radps))
        return next(self._answers)

    def close(self) -> None:
        self._commands.put(None)
        self._answers.cancel()


def test_commands_on_one_call_are_answered_in_order_and_a_refusal_leaves_the_call_open(
        fresh_server: SkillServer) -> None:
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        driver = Driver(robot)
        try:
            first = driver.send(TOKEN, 1, 0.1)
            assert (first.sequence, first.WhichOneof("outcome")) == (1, "ack")
            assert (first.ack.applied_sequence, first.ack.linear_mps) == (1, pytest.approx(0.1))
            refused = driver.send("someone-else", 2, 0.2)
            assert (refused.sequence, refused.WhichOneof("outcome")) == (2, "refusal")
            assert refused.refusal.status_code == grpc.StatusCode.PERMISSION_DENIED.value[0]
            invalid = driver.send(TOKEN, 3, float("nan"))
            assert invalid.WhichOneof("outcome") == "refusal"
            assert invalid.refusal.status_code == grpc.StatusCode.INVALID_ARGUMENT.value[0]
            assert invalid.refusal.field == "linear_mps"
            older = driver.send(TOKEN, 1, 0.3)  # not above the one in force: ignored, the ack says which holds
            assert (older.sequence, older.ack.applied_sequence, older.ack.linear_mps) == (1, 1, pytest.approx(0.1))
            later = driver.send(TOKEN, 4, 0.05, 0.2)
            assert (later.ack.applied_sequence, later.ack.linear_mps, later.ack.angular_radps) == (
                4, pytest.approx(0.05), pytest.approx(0.2))
        finally:
            driver.close()


def test_the_deadman_stops_the_robot_while_the_stream_stays_open_and_silent(fresh_server: SkillServer) -> None:
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        telemetry = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=50), timeout=DEADLINE_S)
        driver = Driver(robot)
        try:
            assert driver.send(TOKEN, 1, 0.2).ack.applied_sequence == 1
            moved = stopped = False
            for message in telemetry:  # the call is open and says nothing more: the deadman still stops the base
                moved |= message.odometry.linear_mps > 0.1
                if moved and message.deadman_stopped and abs(message.odometry.linear_mps) < 0.005:
                    stopped = True
                    break
            assert moved and stopped
        finally:
            telemetry.cancel()
            driver.close()

