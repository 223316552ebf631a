"""The queue channel (each connected user's seat, live, and the pass/leave/join actions), the seat a robot
channel keeps for its user, and the checks every robot channel makes."""

from __future__ import annotations

import asyncio
import time
import weakref

from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy import select

from middleware.access import round_robin
from middleware.access.commands import robot_commands
from middleware.access.coordinator import AccessCoordinator, access_coordinator
from middleware.db import session_factory
from middleware.live.loop import Continuation, blocking_work
from middleware.live.wire import LiveSocket
from middleware.models import User
from middleware.realtime import CLOSE_NOT_FOUND, Channels, WebSocket, as_json, refuse
from middleware.robots.link import RobotLink
from middleware.validation import InvalidInput, parse_message

HEARTBEAT_INTERVAL_S = 2.0
REFRESH_INTERVAL_S = 1.0  # how often a seat is looked at (a turn ending); a change wakes the socket at once
# The page runs these down itself between messages (queue-panel.js): a seat is sent when anything else changes,
# and every RESEND_S besides, not every second to every console.
RUNNING_FIELDS = ("turn_remaining_s", "estimated_wait_s")
RESEND_S = 10.0
ACTIONS = {"pass": round_robin.pass_turn, "leave": round_robin.leave}


def open_robot_channel(ws: WebSocket, robot_name: str) -> RobotLink | None:
    """The robot's link after the check every robot channel makes (a robot this user may reach; `Channels` made
    the login and Origin checks), or None once the socket is refused."""
    link = robot_commands().reachable(robot_name, int(current_user.get_id()))
    if link is None:
        refuse(ws, CLOSE_NOT_FOUND, "unknown_robot", gettext("There is no robot named %(value)s.",
                                                              value=repr(robot_name[:64])), "robot_name")
    return link


class ChannelSeat:
    """A channel's hold on its user's place in the robot's queue: joined once, then kept with heartbeats that
    say when the client was last heard, so a client that vanished without closing loses the seat one grace
    period after it went quiet, however long its socket takes to time out."""

    def __init__(self, robot_name: str, user_id: int) -> None:
        self.robot_name, self.user_id = robot_name, user_id
        self._coordinator = access_coordinator()
        self._heartbeat_at = float("-inf")

    def join(self) -> None:
        """Connects the user to the robot's queue (the first user gets control at once)."""
        self._coordinator.start_ticker()
        self._coordinator.join(self.robot_name, self.user_id)

    def keep(self, ws: WebSocket, *, closing: bool = False) -> None:
        """Tells the queue when ws's client was last heard (at most every HEARTBEAT_INTERVAL_S, and always when the
        socket is closing, so that a reload keeps the whole grace): in memory, written with the process's next
        batch, whose times are the clients' own, so a class closing its consoles at once costs one write."""
        at = time.monotonic()
        if closing or at - self._heartbeat_at >= HEARTBEAT_INTERVAL_S:
            self._coordinator.note_heard(self.robot_name, self.user_id, ws.silent_s())
            self._heartbeat_at = at


class SeatFacts:
    """What queue sockets read besides the queue, shared by this process's sockets: users' names and turn lengths
    (a turn length at most TURN_LENGTH_FRESH_S old, as a tutor may change it)."""

    TURN_LENGTH_FRESH_S = 10.0

    def __init__(self, coordinator: AccessCoordinator) -> None:
        self._coordinator = coordinator
        self._names: dict[int, str | None] = {}
        self._turns: dict[int, tuple[float, float]] = {}

    def known(self, state: round_robin.QueueState, user_id: int) -> bool:
        """Whether seat_message for user_id needs no database read now."""
        read_at, _ = self._turns.get(state.controller_id or user_id, (-float("inf"), 0.0))
        return ((state.controller_id is None or state.controller_id in self._names)
                and time.monotonic() - read_at <= self.TURN_LENGTH_FRESH_S)

    def username(self, user_id: int) -> str | None:
        if user_id not in self._names:
            with session_factory(self._coordinator.app)() as session:
                self._names[user_id] = session.scalar(select(User.username).where(User.id == user_id))
        return self._names[user_id]

    def turn_length_s(self, user_id: int) -> float:
        read_at, length = self._turns.get(user_id, (-float("inf"), 0.0))
        if time.monotonic() - read_at > self.TURN_LENGTH_FRESH_S:
            length = self._coordinator.turn_length_s(user_id)
            self._turns[user_id] = (time.monotonic(), length)
        return length


_shared_facts: weakref.WeakKeyDictionary[AccessCoordinator, SeatFacts] = weakref.WeakKeyDictionary()


def shared_facts(coordinator: AccessCoordinator) -> SeatFacts:
    """The facts every queue socket of this process shares (one read per user, not per socket)."""
    facts = _shared_facts.get(coordinator)
    if facts is None:
        facts = _shared_facts.setdefault(coordinator, SeatFacts(coordinator))
    return facts


def seat_message(coordinator: AccessCoordinator, robot_name: str, user_id: int,
                 facts: SeatFacts | None = None) -> dict[str, object]:
    """The queue as user_id sees it, as a JSON-ready message (from memory until the queue changes)."""
    facts = facts or SeatFacts(coordinator)
    state = coordinator.seen_snapshot(robot_name)
    turn_length_s = facts.turn_length_s(state.controller_id or user_id)
    seat = round_robin.seat_of(state, user_id, coordinator.now(), turn_length_s)
    controller_name = facts.username(state.controller_id) if state.controller_id is not None else None
    return {
        "type": "queue",
        "in_queue": seat.in_queue,
        "is_controller": seat.is_controller,
        "position": seat.position,
        "queue_size": seat.queue_size,
        "pool_waiting": seat.pool_waiting,
        "turn_remaining_s": None if seat.turn_remaining_s is None else round(seat.turn_remaining_s, 1),
        "estimated_wait_s": None if seat.estimated_wait_s is None else round(seat.estimated_wait_s, 1),
        "warning": seat.warning,
        "faulted": seat.faulted,
        "controller": controller_name,
    }


def parse_queue_action(raw: object) -> str:
    """The action named by a queue message, or ValueError with a sentence."""
    try:
        return str(parse_message(raw, ("pass", "leave", "join"), 256)["type"])
    except InvalidInput as invalid:
        raise ValueError(invalid.message) from None


def queue_channel(ws: WebSocket, robot_name: str) -> Continuation | None:
    """Joins the robot's queue and reports the user's seat until the socket closes (the seat outlives it)."""
    if open_robot_channel(ws, robot_name) is None:
        return None
    coordinator = access_coordinator()
    user_id = int(current_user.get_id())
    seat = ChannelSeat(robot_name, user_id)
    seat.join()
    facts = shared_facts(coordinator)
    work = blocking_work()

    def act(action: str) -> None:
        if action == "join":
            coordinator.join(robot_name, user_id)
        else:
            coordinator.apply(ACTIONS[action], robot_name, user_id)

    async def report(live: LiveSocket) -> None:
        loop = asyncio.get_running_loop()

        def changed(robot: str | None) -> None:
            if robot in (None, robot_name):
                loop.call_soon_threadsafe(live.nudge)

        stop_watching = coordinator.watch_queues(changed)  # a turn passing in any worker shows at once
        last_sent: dict[str, object] | None = None
        last_sent_at = 0.0
        try:
            while live.connected:
                raw = await live.receive(timeout=REFRESH_INTERVAL_S)
                seat.keep(live)
                if raw is not None:
                    try:
                        action = parse_queue_action(raw)
                    except ValueError as invalid:
                        await live.send(as_json({"type": "error", "code": "invalid_field", "message": str(invalid),
                                                 "field": "type"}))
                        continue
                    await work(act, action)
                    last_sent = None
                now = time.monotonic()
                if facts.known(coordinator.seen_snapshot(robot_name), user_id):
                    message = seat_message(coordinator, robot_name, user_id, facts)  # from memory: on the loop
                else:
                    message = await work(seat_message, coordinator, robot_name, user_id, facts)
                shown = {key: value for key, value in message.items() if key not in RUNNING_FIELDS}
                if shown != last_sent or now - last_sent_at >= RESEND_S:
                    await live.send(as_json(message))
                    last_sent, last_sent_at = shown, now
        finally:
            stop_watching()
            seat.keep(live, closing=True)

    return report


def register(sock: Channels) -> None:
    """Declares the queue channel."""
    sock.route("/ws/robots/<robot_name>/queue", endpoint="queue_channel")(queue_channel)
