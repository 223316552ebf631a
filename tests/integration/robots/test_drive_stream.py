"""A driver's drive commands reach the robot on one DriveStream call, opened at the first command and reused for every
command (a unary Drive each was a third of a worker's time in a class), answered by sequence; when the call breaks or
the robot has none, each command still arrives as a unary Drive, and the stale-token rule holds on it as before."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Awaitable, Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

import grpc
import pytest

from benchmarks.standin_robots import StandInRobot
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

TOKEN = "driver-token"
T = TypeVar("T")


class BreakingRobot(StandInRobot):
    """A stand-in whose DriveStream breaks (UNAVAILABLE, as when the robot restarts) after three commands."""

    async def DriveStream(self, request_iterator, context):  # noqa: N802 - gRPC's method name
        self.drive_streams += 1
        answered = 0
        async for command in request_iterator:
            if answered == 3:
                await context.abort(grpc.StatusCode.UNAVAILABLE, "the robot went away")
            answered += 1
            yield await self.answer_drive(command)


class UnaryOnlyRobot(StandInRobot):
    """A robot that offers no DriveStream (an older skill server): the call answers UNIMPLEMENTED."""

    async def DriveStream(self, request_iterator, context):  # noqa: N802
        self.drive_streams += 1
        await context.abort(grpc.StatusCode.UNIMPLEMENTED, "no drive streams here")
        yield  # an async generator, as grpc.aio's stream handlers are


class CountingRobot(StandInRobot):
    """A stand-in that counts the DriveStream calls under way."""

    open_streams = 0

    async def DriveStream(self, request_iterator, context):  # noqa: N802
        self.open_streams += 1
        try:
            async for answer in super().DriveStream(request_iterator, context):
                yield answer
        finally:
            self.open_streams -= 1


@pytest.fixture
def serve() -> Iterator[Callable[[StandInRobot], str]]:
    """Serves stand-in robots on grpc.aio servers on a loop of their own; the address of each."""
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    servers: list[grpc.aio.Server] = []

    def start(robot: StandInRobot) -> str:
        async def started() -> int:
            server = grpc.aio.server()
            robot_pb2_grpc.add_RobotServicer_to_server(robot, server)
            port = server.add_insecure_port("127.0.0.1:0")
            await server.start()
            servers.append(server)
            return port

        return f"127.0.0.1:{asyncio.run_coroutine_threadsafe(started(), loop).result(10)}"

    try:
        yield start
    finally:
        for server in servers:
            asyncio.run_coroutine_threadsafe(server.stop(0), loop).result(10)
        loop.call_soon_threadsafe(loop.stop)
        thread.join(5)
        loop.close()


def on_a_loop(address: str, body: Callable[..., Awaitable[T]], rpc_timeout_s: float = 1.0) -> T:
    """body(commander, link) on a loop of its own on a thread of its own (as the channel loop runs), with a Commander
    under the owner's token; the link is closed on that loop."""
    from middleware.access.commands import Commander, OwnerToken
    from middleware.robots.link import RobotLink

    async def run() -> T:
        link = RobotLink("robot-1", address, rpc_timeout_s)
        link.set_controller(TOKEN)
        commander = Commander(link, OwnerToken(link, lambda: TOKEN))
        try:
            return await body(commander, link)
        finally:
            await commander.end_driving()
            link.close()
            await asyncio.sleep(0.1)

    with ThreadPoolExecutor(1) as thread:
        return thread.submit(lambda: asyncio.run(run())).result(60)


async def blocking(fn, *args):  # noqa: ANN001, ANN201 - the channel loop's pool, run inline here
    return fn(*args)


def test_twenty_commands_of_a_driver_travel_on_one_call(serve) -> None:  # noqa: ANN001
    robot = CountingRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> list[int]:  # noqa: ANN001
        applied = [(await commander.drive_async(sequence, 0.1, 0.0, blocking)).applied_sequence
                   for sequence in range(1, 21)]
        assert robot.open_streams == 1
        return applied

    assert on_a_loop(address, drive) == list(range(1, 21))
    assert (robot.drive_streams, robot.drive_calls, robot.drives) == (1, 0, 20)  # before: 0 streams, 20 calls
    deadline = time.monotonic() + 5
    while robot.open_streams and time.monotonic() < deadline:  # the driver left: its call ends on the robot
        time.sleep(0.05)
    assert robot.open_streams == 0


def test_a_broken_stream_falls_back_to_unary_drives_and_the_next_command_still_arrives(serve) -> None:  # noqa: ANN001
    from middleware.robots import drive_stream

    robot = BreakingRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> list[int]:  # noqa: ANN001
        applied = []
        for sequence in range(1, 11):
            applied.append((await commander.drive_async(sequence, 0.1, 0.0, blocking)).applied_sequence)
            await asyncio.sleep(0.01)
        await asyncio.sleep(drive_stream.REOPEN_AFTER_S)  # then the call is opened again
        applied.append((await commander.drive_async(11, 0.1, 0.0, blocking)).applied_sequence)
        return applied

    assert on_a_loop(address, drive) == list(range(1, 12))  # every command arrived, each in turn
    assert robot.drives == 11
    assert robot.drive_calls >= 1  # the command the break caught went as a unary Drive, and those after it
    assert robot.drive_streams == 2  # the call was opened again after the break


def test_a_robot_without_drive_streams_is_driven_by_unary_calls_asked_once(serve) -> None:  # noqa: ANN001
    robot = UnaryOnlyRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> list[int]:  # noqa: ANN001
        return [(await commander.drive_async(sequence, 0.1, 0.0, blocking)).applied_sequence
                for sequence in range(1, 11)]

    assert on_a_loop(address, drive) == list(range(1, 11))
    assert (robot.drive_streams, robot.drive_calls, robot.drives) == (1, 10, 10)


class AnotherControllersRobot(StandInRobot):
    """A robot whose controller is someone else, whatever the middleware hands it (the turn moved on elsewhere)."""

    async def SetController(self, request, context):  # noqa: N802
        self.token = "another-controller"
        return await super().SetController(robot_pb2.SetControllerRequest(token=self.token), context)


def test_a_robot_that_forgot_the_token_gets_it_again_and_the_command_on_the_stream(serve) -> None:  # noqa: ANN001
    """The stale-token rule on a stream's refusal: the robot restarted and forgot its controller; the command path
    hands it the token again and sends the command once more, on the same call."""
    robot = CountingRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> tuple[int, int]:  # noqa: ANN001
        first = (await commander.drive_async(1, 0.1, 0.0, blocking)).applied_sequence
        robot.token = ""  # forgotten, as after a restart
        second = (await commander.drive_async(2, 0.2, 0.0, blocking)).applied_sequence
        return first, second

    assert on_a_loop(address, drive) == (1, 2)
    assert (robot.token, robot.drive_streams, robot.drive_calls) == (TOKEN, 1, 0)


def test_a_command_the_robot_refuses_on_the_stream_is_refused_as_a_unary_one_was(serve) -> None:  # noqa: ANN001
    from middleware.robots.refusals import CommandRefused

    robot = AnotherControllersRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> CommandRefused:  # noqa: ANN001
        with pytest.raises(CommandRefused) as refused:
            await commander.drive_async(1, 0.1, 0.0, blocking)
        return refused.value

    refusal = on_a_loop(address, drive)
    assert (refusal.status, refusal.code, refusal.reason) == (403, "not_controller", "not_controller")
    assert (robot.drive_streams, robot.drive_calls, robot.drives) == (1, 0, 0)


class OnceLateRobot(StandInRobot):
    """A stand-in that answers the second drive command 0.8 s late (a robot's loop held up once)."""

    async def answer_drive(self, request):  # noqa: ANN001, ANN201
        if request.sequence == 2:
            await asyncio.sleep(0.8)
        return await super().answer_drive(request)


def test_a_command_unanswered_in_time_is_refused_and_the_next_ones_still_arrive(serve, monkeypatch) -> None:  # noqa: ANN001
    from middleware.robots import drive_stream
    from middleware.robots.refusals import RobotUnavailable

    monkeypatch.setattr(drive_stream, "ANSWER_WAIT_S", 0.5)  # the link's deadline below, 0.5 s, then applies
    robot = OnceLateRobot("robot-1")
    address = serve(robot)

    async def drive(commander, link) -> list[int]:  # noqa: ANN001
        applied = [(await commander.drive_async(1, 0.1, 0.0, blocking)).applied_sequence]
        with pytest.raises(RobotUnavailable):  # as a unary Drive past its deadline
            await commander.drive_async(2, 0.1, 0.0, blocking)
        applied += [(await commander.drive_async(sequence, 0.1, 0.0, blocking)).applied_sequence
                    for sequence in (3, 4)]  # meanwhile as unary Drives
        await asyncio.sleep(drive_stream.REOPEN_AFTER_S)
        applied.append((await commander.drive_async(5, 0.1, 0.0, blocking)).applied_sequence)  # on a new call
        return applied

    assert on_a_loop(address, drive, rpc_timeout_s=0.5) == [1, 3, 4, 5]
    assert (robot.drive_streams, robot.drive_calls) == (2, 2)
