"""The robot WebSocket channels: camera and telemetry (fanned out), drive (validated, then sent through the
command path), a goal's updates and the localization estimate."""

from __future__ import annotations

import asyncio
import collections
import contextlib
import functools
import logging
import threading
import time
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime

import grpc
from flask import Flask, current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from simple_websocket import ConnectionClosed

from middleware.access.commands import Commander, robot_commands
from middleware.access.graded_runs import graded_run_started_at, open_graded_runs
from middleware.access.sockets import ChannelSeat, open_robot_channel
from middleware.assessment.hidden_obstacles import CAMERA_REFUSAL, OBSTACLES_HIDDEN, hiding_book
from middleware.auth.schemas import InvalidField
from middleware.db import session_factory
from middleware.lab.schemas import GOAL_ID_PATTERN, DriveLimits, DriveRequest, parse_drive_message
from middleware.live.loop import Continuation, blocking_work
from middleware.live.wire import LiveSocket
from middleware.realtime import (
    CLOSE_FORBIDDEN,
    CLOSE_NOT_FOUND,
    CLOSE_TRY_AGAIN_LATER,
    Channels,
    ViewerHold,
    WebSocket,
    as_json,
    parse_ping,
    pong,
    refuse,
    relay_stream,
    send_json,
    viewer_hold,
)
from middleware.robots.fanout import FanoutHub
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.messages import FINAL_GOAL_STATUSES, goal_update_message

log = logging.getLogger(__name__)

DRIVE_SEND_INTERVAL_MS = 50
# 20 commands a second and the pings, with room for a burst after the network stalled.
DRIVE_MESSAGES_PER_S = 50
RECEIVE_WAIT_S = 2.0


ZONE_TEST_RECHECK_S = 2.0  # how soon an obstacle-zone test begun while the camera is open closes it


def obstacles_hidden_from(user_id: int) -> bool:
    """Whether user_id's obstacle-zone test is in progress now (this process's book; assessment/hidden_obstacles)."""
    return hiding_book(current_app).hides(user_id)


def camera_relay(ws: WebSocket, hub: FanoutHub[bytes], hold: ViewerHold | None = None) -> Continuation | None:
    """A camera's frames for the current user, refused while their obstacle-zone test is in progress (the picture
    shows the obstacles), and closed with the same sentence when one begins while they watch."""
    user_id = int(current_user.get_id())
    if obstacles_hidden_from(user_id):
        refuse(ws, CLOSE_FORBIDDEN, OBSTACLES_HIDDEN, CAMERA_REFUSAL)
        return None
    work = blocking_work()

    async def relay(live: LiveSocket) -> None:
        async def close_when_a_zone_test_begins() -> None:
            while not await work(obstacles_hidden_from, user_id):
                await asyncio.sleep(ZONE_TEST_RECHECK_S)
            with contextlib.suppress(ConnectionClosed):
                await live.send(as_json({"type": "error", "code": OBSTACLES_HIDDEN, "message": CAMERA_REFUSAL,
                                         "field": None}))
            await live.close(CLOSE_FORBIDDEN, CAMERA_REFUSAL[:120])

        watcher = asyncio.ensure_future(close_when_a_zone_test_begins())
        try:
            await relay_stream(live, hub, hold=hold)
        finally:
            watcher.cancel()

    return relay


def camera_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """Camera frames, packed once per frame for every viewer (none during the viewer's obstacle-zone test)."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return None
    return camera_relay(ws, link.camera, viewer_hold(robot_name, int(current_user.get_id())))


def telemetry_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """Odometry, sonar and laser readings, and where the robot truly stands for the camera drawn in the browser;
    never that to a user in a graded run on the robot (their drawn camera gives way to the server's)."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return None
    return truth_hidden_in_graded_runs(robot_name, link.telemetry, True)


def measured_round_trip_ms(link: RobotLink) -> float | None:
    """A fresh middleware-to-robot round trip in ms, or None when the robot does not answer."""
    try:
        return link.measure_round_trip_ms()
    except RobotUnavailable:
        return None


# (robot, user) -> how long that user's commands to the robot are held now (an experiment trial's distant proxy);
# composed in create_app (hold_commands_with), none by default.
CommandHold = Callable[[str, int], Callable[[], float]]
_COMMAND_HOLD_KEY = "telelab.command_hold"
COMMAND_HOLD_RECHECK_S = 1.0


def hold_commands_with(app: Flask, hold: CommandHold) -> None:
    """The drive channel holds each user's commands as hold says (create_app hands in the experiment's)."""
    app.extensions[_COMMAND_HOLD_KEY] = hold


def _no_hold(robot_name: str, user_id: int) -> Callable[[], float]:
    return lambda: 0.0


class HeldCommands:
    """A driver's commands held for the delay in force when each arrived, sent in arrival order once due: the
    thesis' distant proxy, on the commands as the relay does it on the video. Reading the delay may reach the
    database, so it is read off the loop, at most every COMMAND_HOLD_RECHECK_S."""

    def __init__(self, read_delay_s: Callable[[], float], work: Callable[..., Awaitable[object]]) -> None:
        self._read, self._work = read_delay_s, work
        self._delay_s, self._checked_at = 0.0, float("-inf")
        self._queue: asyncio.Queue[tuple[float, Callable[[], Awaitable[None]]]] = asyncio.Queue()
        self._sender: asyncio.Task[None] | None = None

    async def delay_s(self) -> float:
        loop = asyncio.get_running_loop()
        if loop.time() - self._checked_at >= COMMAND_HOLD_RECHECK_S:
            self._checked_at = loop.time()
            with contextlib.suppress(Exception):  # a database hiccup keeps the last known delay
                self._delay_s = float(await self._work(self._read))  # type: ignore[arg-type]
        return self._delay_s

    def send_later(self, due: float, send: Callable[[], Awaitable[None]]) -> None:
        """Sends at due (the loop's clock), after every command queued before."""
        self._queue.put_nowait((due, send))
        if self._sender is None:
            self._sender = asyncio.get_running_loop().create_task(self._send_in_order())

    @property
    def holding(self) -> bool:
        return self._sender is not None and not self._queue.empty()

    async def _send_in_order(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            due, send = await self._queue.get()
            await asyncio.sleep(max(0.0, due - loop.time()))
            await send()

    async def close(self) -> None:
        """Drops what is still held (the socket closed: the stop that follows is not held)."""
        if self._sender is not None:
            self._sender.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._sender


def drive_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """Drive commands: validated here, sent through the command path (held first while an experiment trial delays
    them); the robot stops at once when the socket closes."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return None
    try:
        info = link.info()
    except RobotUnavailable as offline:
        refuse(ws, CLOSE_TRY_AGAIN_LATER, offline.code, offline.message)
        return None
    user_id = int(current_user.get_id())
    seat = ChannelSeat(robot_name, user_id)
    seat.join()
    robot = robot_commands().for_user(robot_name, user_id)
    limits = DriveLimits(info.max_linear_mps, info.max_angular_radps)
    sequence_base = link.reserve_sequences()
    send_json(ws, {
        "type": "ready",
        "max_linear_mps": limits.max_linear_mps,
        "max_angular_radps": limits.max_angular_radps,
        "send_interval_ms": DRIVE_SEND_INTERVAL_MS,
        "sequence_base": sequence_base,
        "is_controller": robot.is_controller(),
    })
    work = blocking_work()
    hold = current_app.extensions.get(_COMMAND_HOLD_KEY, _no_hold)(robot_name, user_id)

    async def drive(live: LiveSocket) -> None:
        last_sequence = 0
        held = HeldCommands(hold, work)

        async def send(command: DriveRequest, superseded: int = 0) -> None:
            try:
                result = await robot.drive_async(sequence_base + command.sequence, command.linear_mps,
                                                 command.angular_radps, work)
            except (CommandRefused, RobotUnavailable) as refused:
                await live.send(as_json({"type": "error", "code": refused.code, "message": refused.message,
                                         "field": refused.field}))
                return
            await live.send(as_json({
                "type": "ack",
                "sequence": command.sequence,
                "applied_sequence": max(0, result.applied_sequence - sequence_base),
                "linear_mps": result.linear_mps,
                "angular_radps": result.angular_radps,
                "robot_rtt_ms": round(result.round_trip_ms, 3),
                "superseded": superseded,
            }))

        async def answer_ping(ping_id: int) -> None:
            measured = await work(measured_round_trip_ms, link)
            await live.send(as_json(pong(ping_id, functools.partial(lambda ms: ms, measured))))

        async def error(invalid: InvalidField) -> None:
            await live.send(as_json({"type": "error", "code": "invalid_field", "message": invalid.message,
                                     "field": invalid.field}))

        # The commands read and not sent yet, with when each arrived. Reading the driver's messages never waits for
        # the robot or the pool: they cannot pile up to the channel's bound, which closes the channel (a lost seat).
        waiting: collections.deque[tuple[DriveRequest, float]] = collections.deque()
        arrived = asyncio.Event()

        async def send_in_turn() -> None:
            while True:
                await arrived.wait()
                arrived.clear()
                while waiting:
                    delay_s = await held.delay_s()
                    if delay_s > 0 or held.holding:  # held for the delay from its arrival, each in turn
                        command, at = waiting.popleft()
                        held.send_later(at + delay_s, functools.partial(send, command))
                        continue
                    # Behind (a slow robot, a busy worker): the newest velocity supersedes those before it, so the
                    # robot never works through seconds-old commands in turn.
                    command, _at = waiting.pop()
                    superseded = len(waiting)
                    waiting.clear()
                    await send(command, superseded)

        sending = asyncio.ensure_future(send_in_turn())
        try:
            while True:
                raw = await live.receive(timeout=RECEIVE_WAIT_S)
                seat.keep(live)  # an idle driver still holds the seat while its client answers pings
                if sending.done():
                    sending.result()  # the sender failed (the socket closed): the channel ends as it would have
                if raw is None:
                    continue
                ping_id = parse_ping(raw)
                if ping_id is not None:
                    await answer_ping(ping_id)
                    continue
                try:
                    command = parse_drive_message(raw, limits, last_sequence)
                except InvalidField as invalid:
                    await error(invalid)
                    continue
                last_sequence = command.sequence
                waiting.append((command, asyncio.get_running_loop().time()))
                arrived.set()
        finally:
            sending.cancel()
            with contextlib.suppress(asyncio.CancelledError, ConnectionClosed):
                await sending
            await held.close()
            await robot.end_driving()
            await work(_stop_quietly, robot, sequence_base + last_sequence + 1)
            seat.keep(live, closing=True)

    return drive


def _stop_quietly(robot: Commander, sequence: int) -> None:
    """Stops the base when a driver leaves; the robot's deadman covers a failure here."""
    try:
        robot.drive(sequence, 0.0, 0.0)
    except (CommandRefused, RobotUnavailable) as error:
        log.info("stop after the driver left %s failed: %s", robot.robot_name, error)


def sees_ground_truth() -> bool:
    """Whether the current user's teaching mode shows the simulator's ground truth."""
    return current_user.role in current_app.config["GROUND_TRUTH_ROLES"]


def goal_channel(ws: WebSocket, robot_name: str, goal_id: str) -> Continuation | None:
    """Relays one goal's state, events and feedback; closes after its final state."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return None
    if not GOAL_ID_PATTERN.fullmatch(goal_id):
        refuse(ws, CLOSE_NOT_FOUND, "unknown_goal", gettext("There is no goal with that id."), "goal_id")
        return None

    async def relay(live: LiveSocket) -> None:
        updates = link.watch_goal(goal_id)
        try:
            async for update in updates:
                message = goal_update_message(update)
                await live.send(as_json(message))
                goal = message.get("goal")
                if message["type"] == "goal" and isinstance(goal, dict) and goal.get("status") in FINAL_GOAL_STATUSES:
                    break
        except grpc.RpcError as error:
            code = "unknown_goal" if error.code() == grpc.StatusCode.NOT_FOUND else "robot_offline"
            await live.send(as_json({"type": "error", "code": code,
                                     "message": error.details() or "The robot is not answering.",
                                     "field": "goal_id" if code == "unknown_goal" else None}))
        finally:
            await updates.aclose()

    return relay


GRADED_RUN_RECHECK_S = 1.0  # how soon a graded run begun while the panel is open hides the ground truth


def in_graded_run(robot_name: str, user_id: int) -> bool:
    """Whether user_id's experimental attempt or delay trial on robot_name is open now (a database read)."""
    with session_factory(current_app)() as session:
        return graded_run_started_at(session, robot_name, user_id, datetime.now(UTC)) is not None


class GradedRunBook:
    """The graded runs open now, read for the whole process at most every GRADED_RUN_RECHECK_S. Each socket showing
    the truth asks every second whether its viewer's run began: a query each was two a second for every console (a
    class of 50: a hundred), which kept the sockets' pool, and the drive commands waiting behind it, busy."""

    def __init__(self, app: Flask) -> None:
        self._sessions = session_factory(app)
        self._lock = threading.Lock()
        self._open: set[tuple[str, int]] = set()
        self._read_at = float("-inf")

    def holds(self, robot_name: str, user_id: int) -> bool:
        """Whether user_id's graded run on robot_name is open (as read at most GRADED_RUN_RECHECK_S ago)."""
        with self._lock:  # one reader a second; the others wait for its answer rather than ask again
            if time.monotonic() - self._read_at >= GRADED_RUN_RECHECK_S:
                started = time.monotonic()
                with self._sessions() as session:
                    self._open = open_graded_runs(session, datetime.now(UTC))
                self._read_at = started
            return (robot_name, user_id) in self._open


_GRADED_RUNS_KEY = "telelab.graded_run_book"


def still_in_graded_run(robot_name: str, user_id: int) -> bool:
    """in_graded_run from the process's book (one read a second for every socket; on the pool)."""
    book = current_app.extensions.get(_GRADED_RUNS_KEY)
    if book is None:
        book = current_app.extensions.setdefault(_GRADED_RUNS_KEY, GradedRunBook(current_app))
    return bool(book.holds(robot_name, user_id))


def localization_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """The localization estimate, particles and errors; the ground truth only where the teaching mode allows, and
    never to a user in a graded run on the robot (a "report your pose" question must not be read off the panel)."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return None
    return truth_hidden_in_graded_runs(robot_name, link.localization, sees_ground_truth())


def truth_hidden_in_graded_runs(robot_name: str, hub: FanoutHub, shown: bool) -> Continuation:
    """Relays hub's messages packed (with the truth, without it): the first while shown and the user is in no
    graded run on the robot, the second from the moment one begins (checked every GRADED_RUN_RECHECK_S). Every
    stream relayed here shows where the robot is, so each is held by the viewer's injected delay, as the camera is."""
    user_id = int(current_user.get_id())
    hold = viewer_hold(robot_name, user_id)
    truth = [shown and not in_graded_run(robot_name, user_id)]
    work = blocking_work()

    async def relay(live: LiveSocket) -> None:
        async def hide_truth_when_a_graded_run_begins() -> None:
            while truth[0]:
                await asyncio.sleep(GRADED_RUN_RECHECK_S)
                truth[0] = not await work(still_in_graded_run, robot_name, user_id)

        watcher = asyncio.ensure_future(hide_truth_when_a_graded_run_begins())
        try:
            await relay_stream(live, hub, choose=lambda versions: versions[0 if truth[0] else 1], hold=hold)
        finally:
            watcher.cancel()

    return relay


def register(sock: Channels) -> None:
    """Declares the robot channels."""
    sock.route("/ws/robots/<robot_name>/camera")(camera_channel)
    sock.route("/ws/robots/<robot_name>/telemetry")(telemetry_channel)
    sock.route("/ws/robots/<robot_name>/drive", messages_per_s=DRIVE_MESSAGES_PER_S)(drive_channel)
    sock.route("/ws/robots/<robot_name>/goals/<goal_id>")(goal_channel)
    sock.route("/ws/robots/<robot_name>/localization")(localization_channel)
