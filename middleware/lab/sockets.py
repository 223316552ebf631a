"""The robot WebSocket channels: camera and telemetry (fanned out), and drive (validated, forwarded)."""

from __future__ import annotations

import json
import logging
import time
from urllib.parse import urlsplit

from flask import Flask, request
from flask_login import current_user
from flask_sock import Sock
from simple_websocket import ConnectionClosed

from middleware.access.coordinator import access_coordinator
from middleware.auth.schemas import InvalidField
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lab.delay import DelayQueue, ViewerDelay, apply_viewer_delay, capture_time_s, viewer_delay
from middleware.lab.schemas import DriveLimits, parse_drive_message
from middleware.robots.fanout import FanoutHub
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.registry import robot_registry

log = logging.getLogger(__name__)
sock = Sock()

# Close codes the client knows: it does not reconnect after these.
CLOSE_NOT_LOGGED_IN = 4401
CLOSE_FORBIDDEN = 4403
CLOSE_UNKNOWN_ROBOT = 4404
CLOSE_TRY_AGAIN_LATER = 1013
DRIVE_SEND_INTERVAL_MS = 50
STREAM_POLL_S = 0.5
CLOSE_HANDSHAKE_WAIT_S = 1.0
HEARTBEAT_INTERVAL_S = 2.0


def init_app(app: Flask) -> None:
    """Registers the channels; incoming messages are small, and idle sockets are pinged."""
    app.config.setdefault("SOCK_SERVER_OPTIONS", {"ping_interval": 20, "max_message_size": 4096})
    sock.init_app(app)

    @app.before_request
    def _websocket_only():  # type: ignore[no-untyped-def]
        if request.path.startswith("/ws/") and request.headers.get("Upgrade", "").lower() != "websocket":
            raise ApiError(400, "websocket_required", "This address takes WebSocket connections only.")


def send_json(ws, message: dict[str, object]) -> None:  # type: ignore[no-untyped-def]
    """Sends message as compact JSON text."""
    ws.send(json.dumps(message, separators=(",", ":")))


def _refuse(ws, close_code: int, code: str, message: str, field: str | None = None) -> None:  # type: ignore[no-untyped-def]
    send_json(ws, {"type": "error", "code": code, "message": message, "field": field})
    ws.close(reason=close_code, message=message[:120])
    # Wait for the client's closing frame: a socket torn down with it unread is reset, and the reset
    # can discard our error message before the client reads it.
    ws.thread.join(CLOSE_HANDSHAKE_WAIT_S)


def _same_origin() -> bool:
    origin = request.headers.get("Origin")
    # Browsers always send Origin on WebSockets; its absence means a non-browser client, not a hijack.
    return origin is None or urlsplit(origin).netloc == request.host


def open_robot_channel(ws, robot_name: str) -> RobotLink | None:  # type: ignore[no-untyped-def]
    """The robot's link after the checks every channel makes, or None once the socket is refused."""
    if not current_user.is_authenticated:
        _refuse(ws, CLOSE_NOT_LOGGED_IN, "not_logged_in", "Your session has ended. Log in again.")
        return None
    # A socket lives for hours: release the database connection the login check used.
    get_session().close()
    if not _same_origin():
        _refuse(ws, CLOSE_FORBIDDEN, "forbidden_origin", "This page may not open the robot's channels.")
        return None
    link = robot_registry().get(robot_name)
    if link is None:
        _refuse(ws, CLOSE_UNKNOWN_ROBOT, "unknown_robot", f"There is no robot named {robot_name!r}.", "robot_name")
        return None
    return link


def relay_stream(ws, hub: FanoutHub, choose=None, delay: ViewerDelay | None = None) -> None:  # type: ignore[no-untyped-def]
    """Sends the hub's newest message whenever there is one, and status changes, until the socket closes.

    choose picks this viewer's version of a message packed in several versions (e.g. with or without
    the ground truth). delay, when given, holds each message until its capture time + the viewer's injected
    delay (middleware/lab/delay.py); a change of delay is announced as {"type": "status", "injected_delay_s"}.
    """
    subscription = hub.subscribe()
    held = DelayQueue(0.0)
    try:
        while ws.connected:
            status = subscription.status_change()
            if status is not None:
                send_json(ws, {"type": "status", "robot_online": status.online, "message": status.message})
            delay_s = apply_viewer_delay(ws, delay, held, hub.status_with_version()[0].online)
            wait_s = held.seconds_until_next(time.time())
            message = subscription.next_message(STREAM_POLL_S if wait_s is None else min(wait_s, STREAM_POLL_S))
            if message is not None:
                message = message if choose is None else choose(message)
                if delay_s > 0 or len(held):  # after a delay ends, the held ones go first
                    held.push(message, capture_time_s(message), time.time())
                else:
                    ws.send(message)
            for due in held.pop_due(time.time()):
                ws.send(due)
            while ws.receive(timeout=0) is not None:
                pass  # nothing is expected from viewers; drop it so it cannot pile up
    except (ConnectionClosed, OSError):
        pass  # the viewer went (a closed tab mid-send): the end of this stream, not an error to log
    finally:
        subscription.close()


@sock.route("/ws/robots/<robot_name>/camera")
def camera_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
    """Camera frames, packed once per frame for every viewer."""
    link = open_robot_channel(ws, robot_name)
    if link is not None:
        relay_stream(ws, link.camera, delay=viewer_delay())


@sock.route("/ws/robots/<robot_name>/telemetry")
def telemetry_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
    """Odometry, sonar and laser readings."""
    link = open_robot_channel(ws, robot_name)
    if link is not None:
        relay_stream(ws, link.telemetry, delay=viewer_delay())


class DriverSeat:
    """The drive socket's view of its user's control: the token, re-read at most every TOKEN_TTL_S."""

    TOKEN_TTL_S = 0.25

    def __init__(self, robot_name: str, user_id: int) -> None:
        self.robot_name, self.user_id = robot_name, user_id
        self._coordinator = access_coordinator()
        self._token: str | None = None
        self._read_at = float("-inf")
        self._heartbeat_at = float("-inf")

    def join(self) -> None:
        """Connects the driver to the robot's queue (the first user gets control at once)."""
        self._coordinator.start_ticker()
        self._coordinator.join(self.robot_name, self.user_id)

    def token(self, fresh: bool = False) -> str | None:
        """The user's controller token, or None while they observe; keeps their seat alive."""
        now = time.monotonic()
        if now - self._heartbeat_at >= HEARTBEAT_INTERVAL_S:
            self._coordinator.heartbeat(self.robot_name, self.user_id)
            self._heartbeat_at = now
        if fresh or now - self._read_at >= self.TOKEN_TTL_S:
            self._token = self._coordinator.controller_token(self.robot_name, self.user_id)
            self._read_at = now
        return self._token

    def resend_token(self) -> bool:
        """Hands the robot this user's token again (a restarted skill server forgets it)."""
        token = self.token(fresh=True)
        if token is None:
            return False
        return self._coordinator.sync_token(self._coordinator.snapshot(self.robot_name), force=True)


def forward_drive(link: RobotLink, seat: DriverSeat, sequence: int, linear_mps: float, angular_radps: float):  # type: ignore[no-untyped-def]
    """Drives under the user's token; None with the user observing. Retries once if the robot forgot the token."""
    token = seat.token()
    if token is None:
        return None
    try:
        return link.drive(token, sequence, linear_mps, angular_radps)
    except CommandRefused as refused:
        if refused.code not in {"not_controller", "unauthenticated"} or not seat.resend_token():
            raise
        token = seat.token(fresh=True)
        return None if token is None else link.drive(token, sequence, linear_mps, angular_radps)


@sock.route("/ws/robots/<robot_name>/drive")
def drive_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
    """Drive commands: validated here, forwarded under the controller's token; the robot stops when it closes."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return
    try:
        info = link.info()
    except RobotUnavailable as error:
        _refuse(ws, CLOSE_TRY_AGAIN_LATER, "robot_offline", f"{error} Try again in a moment.")
        return
    seat = DriverSeat(robot_name, int(current_user.get_id()))
    seat.join()
    limits = DriveLimits(info.max_linear_mps, info.max_angular_radps)
    sequence_base = link.reserve_sequences()
    send_json(ws, {
        "type": "ready",
        "max_linear_mps": limits.max_linear_mps,
        "max_angular_radps": limits.max_angular_radps,
        "send_interval_ms": DRIVE_SEND_INTERVAL_MS,
        "sequence_base": sequence_base,
        "is_controller": seat.token() is not None,
    })
    last_sequence = 0
    try:
        while True:
            raw = ws.receive(timeout=HEARTBEAT_INTERVAL_S)
            if raw is None:
                seat.token()  # an idle driver still holds the seat
                continue
            ping_id = parse_ping(raw)
            if ping_id is not None:
                send_json(ws, pong(link, ping_id))
                continue
            try:
                command = parse_drive_message(raw, limits, last_sequence)
            except InvalidField as invalid:
                send_json(ws, {"type": "error", "code": "invalid_field", "message": invalid.message,
                               "field": invalid.field})
                continue
            last_sequence = command.sequence
            try:
                result = forward_drive(link, seat, sequence_base + command.sequence, command.linear_mps,
                                       command.angular_radps)
            except CommandRefused as refused:
                send_json(ws, {"type": "error", "code": refused.code, "message": refused.message,
                               "field": refused.field})
                continue
            except RobotUnavailable as error:
                send_json(ws, {"type": "error", "code": "robot_offline", "message": str(error), "field": None})
                continue
            if result is None:
                send_json(ws, {"type": "error", "code": "not_controller", "field": None,
                               "message": "You are observing: someone else has control. Wait for your turn."})
                continue
            send_json(ws, {
                "type": "ack",
                "sequence": command.sequence,
                "applied_sequence": max(0, result.applied_sequence - sequence_base),
                "linear_mps": result.linear_mps,
                "angular_radps": result.angular_radps,
                "robot_rtt_ms": round(result.round_trip_ms, 3),
            })
    finally:
        _stop_quietly(link, seat, sequence_base + last_sequence + 1)


def parse_ping(raw: object) -> int | None:
    """The id of a {"type": "ping", "id": n} message, or None for anything else."""
    if not isinstance(raw, str) or len(raw) > 128 or '"ping"' not in raw:
        return None
    try:
        message = json.loads(raw)
    except ValueError:
        return None
    if isinstance(message, dict) and message.get("type") == "ping":
        ping_id = message.get("id")
        if isinstance(ping_id, int) and not isinstance(ping_id, bool) and 0 <= ping_id < 2**53:
            return ping_id
    return None


def pong(link: RobotLink, ping_id: int) -> dict[str, object]:
    """The answer to a ping, with a fresh middleware-to-robot round trip."""
    try:
        robot_rtt_ms: float | None = round(link.measure_round_trip_ms(), 3)
    except RobotUnavailable:
        robot_rtt_ms = None
    return {"type": "pong", "id": ping_id, "robot_rtt_ms": robot_rtt_ms}


def _stop_quietly(link: RobotLink, seat: DriverSeat, sequence: int) -> None:
    """Stops the base when a driver leaves; the robot's deadman covers a failure here."""
    try:
        forward_drive(link, seat, sequence, 0.0, 0.0)
    except (CommandRefused, RobotUnavailable) as error:
        log.info("stop after the driver left %s failed: %s", link.name, error)
