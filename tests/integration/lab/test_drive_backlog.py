"""A driver whose commands arrive faster than the robot answers them (a slow robot, a busy worker) keeps their drive
channel: the channel sends the newest velocity waiting and acknowledges it with how many older ones it superseded,
so the waiting messages never reach the channel's bound, which closed the channel (the class-of-50 benchmark's lost
seats), and the robot never works through seconds-old commands in turn."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import grpc
import pytest

from benchmarks.standin_robots import StandInRobot
from protos.telelab.v1 import robot_pb2_grpc
from tests.conftest import LabClient, LiveServer, _let_go, make_test_app
from tests.integration.lab.test_robot_channels import receive_json

DRIVE_ANSWER_S = 0.2  # the robot's Drive takes this long: it answers 5 of the console's 20 commands a second
DRIVE_HZ = 20
DRIVEN_S = 4.0  # before the fix, 15 commands a second piled up: the bound (50) was passed in about 3.3 s


class SlowRobot(StandInRobot):
    """A stand-in robot (the robot protocol without physics) that answers each drive command (a unary Drive or one
    on the driver's DriveStream) DRIVE_ANSWER_S late."""

    async def answer_drive(self, request):  # noqa: ANN001, ANN201 - the stand-in's hook
        await asyncio.sleep(DRIVE_ANSWER_S)
        return await super().answer_drive(request)


@pytest.fixture
def slow_robot_address() -> Iterator[str]:
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()

    async def start() -> tuple[grpc.aio.Server, int]:
        server = grpc.aio.server()
        robot_pb2_grpc.add_RobotServicer_to_server(SlowRobot("slow-1"), server)
        port = server.add_insecure_port("127.0.0.1:0")
        await server.start()
        return server, port

    server, port = asyncio.run_coroutine_threadsafe(start(), loop).result(10)
    try:
        yield f"127.0.0.1:{port}"
    finally:
        asyncio.run_coroutine_threadsafe(server.stop(0), loop).result(10)
        loop.call_soon_threadsafe(loop.stop)
        thread.join(5)
        loop.close()


def test_a_driver_ahead_of_a_slow_robot_keeps_the_channel_and_the_robot_gets_the_newest_command(
        tmp_path: Path, slow_robot_address: str) -> None:
    from middleware.db import session_factory

    app = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", f"slow-1={slow_robot_address}", tmp_path)
    server = LiveServer(app)
    try:
        client = LabClient(server.url)
        assert client.login() == 302
        drive = client.websocket("/ws/robots/slow-1/drive")
        ready = receive_json(drive)
        assert ready["type"] == "ready" and ready["is_controller"], ready
        acks: list[dict] = []
        sequence, started = 0, time.monotonic()
        while time.monotonic() - started < DRIVEN_S:
            sequence += 1
            drive.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": 0.1, "angular_radps": 0}))
            time.sleep(1 / DRIVE_HZ)
            while (message := _waiting(drive)) is not None:
                assert message["type"] == "ack", message  # before the fix: the channel closed (1008, "faster")
                acks.append(message)
        assert drive.connected, f"the drive channel closed: {drive.close_reason} {drive.close_message}"
        deadline = time.monotonic() + 5
        while (not acks or acks[-1]["sequence"] < sequence) and time.monotonic() < deadline:
            message = receive_json(drive, max(0.1, deadline - time.monotonic()))
            assert message["type"] == "ack", message
            acks.append(message)
        assert acks[-1]["sequence"] == sequence, "the driver's last command never reached the robot"
        answered = {ack["sequence"] for ack in acks}
        assert len(answered) + sum(ack["superseded"] for ack in acks) == sequence  # each sent or superseded
        assert sum(ack["superseded"] for ack in acks) > 0  # the robot answers 5 a second of the 20
        assert all(ack["applied_sequence"] == ack["sequence"] for ack in acks)  # never an old one after a newer
        drive.close()
    finally:
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()


def _waiting(ws) -> dict | None:
    """A message that has arrived already, or None."""
    try:
        return receive_json(ws, 0.001)
    except (AssertionError, TimeoutError):
        return None
