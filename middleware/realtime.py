"""The WebSocket extension and the plumbing every channel shares: bounded inbound messages, the login and
Origin checks, close codes, refuse(), relaying a fanned-out stream, ping/pong.

Each area declares its channels in its own `sockets.py` with a `register(sock)` function; `create_app`
calls them, so no channel exists by the side effect of an import. Every channel declared through
`Channels.route` gets a `ChannelSocket` and the checks of `open_channel` before its handler runs.
"""

from __future__ import annotations

import contextlib
import json
import math
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterable
from functools import wraps
from typing import Any
from urllib.parse import urlsplit

from flask import Flask, Response, current_app, request
from flask_login import current_user
from flask_sock import Sock
from simple_websocket import ConnectionClosed, Server
from wsproto.events import CloseConnection
from wsproto.utilities import LocalProtocolError

from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lab.delay import DelayQueue, ViewerDelay, apply_viewer_delay, capture_time_s
from middleware.robots.fanout import FanoutHub

# Close codes the client knows: it does not reconnect after these.
CLOSE_NOT_LOGGED_IN = 4401
CLOSE_FORBIDDEN = 4403
CLOSE_NOT_FOUND = 4404
CLOSE_TRY_AGAIN_LATER = 1013
CLOSE_GOING_AWAY = 1001
CLOSE_SERVICE_RESTART = 1012  # this worker is leaving (a rolling restart): the client reconnects to another
# A client over its inbound limits (RFC 6455's "policy violation"); it may reconnect, with its backoff.
CLOSE_TOO_MANY_MESSAGES = 1008
STREAM_POLL_S = 0.5
CLOSE_HANDSHAKE_WAIT_S = 1.0
# A live client answers each ping, so it is heard at least this often; one that does not answer by the next
# ping is closed (simple_websocket's rule), and a seat counts its grace from when its client was last heard.
PING_INTERVAL_S = 5.0
# A socket outlives the request that opened it: its login is checked again this often, so a logout, a password
# change or a disabled account closes it (CLOSE_NOT_LOGGED_IN) within this time, in every worker.
LOGIN_RECHECK_S = 5.0
MAX_MESSAGE_BYTES = 4096
# Channels take a person's actions (a click, a chat line) and pings; the drive channel declares more.
DEFAULT_MESSAGES_PER_S = 10
# Open sockets per user in one process: a console tab holds about eight, so a few tabs fit; each socket costs
# a thread, so a script opening thousands is refused (429) before the handshake.
MAX_SOCKETS_PER_USER = 40
# How long a user closed for flooding a channel is refused on it: reconnecting buys no fresh allowance.
FLOOD_COOL_DOWN_S = 10.0

# Set in the WSGI environ once a request was served as a WebSocket (serve.py then writes no HTTP answer).
WEBSOCKET_ENDED = "telelab.websocket_ended"

WebSocket = Any  # simple_websocket.Server: the library ships no type information


class InboundQueue:
    """The messages a channel received and has not handled yet: at most per_s a second are admitted (bursts
    included), and at most per_s wait. Past either, everything waiting is dropped and `overflow` says why: the
    socket is then closed, not left to queue work.

    simple_websocket's reader thread appends; the channel's handler pops.
    """

    def __init__(self, per_s: int) -> None:
        self.per_s = per_s
        self.capacity = per_s
        self.overflow: str | None = None
        self._messages: deque[str | bytes] = deque()
        self._allowance = float(self.capacity)
        self._refilled_at = time.monotonic()

    def append(self, message: str | bytes) -> None:
        """Admits message, or drops it and everything waiting when the client is over its limits."""
        if self.overflow is not None:
            return
        now = time.monotonic()
        self._allowance = min(self.capacity, self._allowance + (now - self._refilled_at) * self.per_s)
        self._refilled_at = now
        if self._allowance < 1:
            self.overflow = f"Too many messages: this channel takes at most {self.per_s} a second."
        elif len(self._messages) >= self.capacity:
            self.overflow = "Messages came faster than this channel can handle them."
        else:
            self._allowance -= 1
            self._messages.append(message)
            return
        self._messages.clear()

    def pop(self) -> str | bytes | None:
        """The oldest waiting message, or None."""
        return self._messages.popleft() if self._messages else None

    def __len__(self) -> int:
        return len(self._messages)


_open_sockets: weakref.WeakSet[ChannelSocket] = weakref.WeakSet()
_draining = threading.Event()


def drain_channels() -> None:
    """This worker is leaving: every channel closes with CLOSE_SERVICE_RESTART at its next receive or send, and
    wakes now if it waits for a message. Safe in a signal handler: it only sets events."""
    _draining.set()
    for ws in list(_open_sockets):
        ws.event.set()


class ChannelSocket(Server):
    """simple_websocket's server socket with a bounded inbound queue, closed with CLOSE_TOO_MANY_MESSAGES when
    its client exceeds it, and the time its client was last heard (any frame: a message, a pong, its close).

    simple_websocket's own reader thread keeps every message in an unbounded list: a flooding client grew the
    process by the flood and kept the handler busy long after it ended.
    """

    def __init__(self, environ: dict[str, Any], messages_per_s: int, **options: Any) -> None:
        self.inbound = InboundQueue(messages_per_s)
        self.heard_at = time.monotonic()
        self.on_overflow: Callable[[], None] = lambda: None  # called once, by the reader thread
        self.login_still_open: Callable[[], bool] = lambda: True  # asked by the handler's thread
        self._login_checked_at = time.monotonic()
        self._closing_since: float | None = None
        super().__init__(environ, **options)
        _open_sockets.add(self)

    def handshake(self) -> None:
        """Installs the bounded queue: Base.__init__ calls this after making its list, before its reader starts."""
        self.input_buffer = self.inbound
        super().handshake()

    def silent_s(self) -> float:
        """Seconds since the client was last heard."""
        return time.monotonic() - self.heard_at

    def _handle_events(self) -> bool:
        # The reader thread calls this whenever bytes arrived from the client.
        self.heard_at = time.monotonic()
        keep_going: bool = super()._handle_events()
        if keep_going and self.inbound.overflow is not None:
            return self._close_for_overflow(self.inbound.overflow)
        return keep_going

    def _close_for_overflow(self, reason: str) -> bool:
        """Sends the closing frame once, then reads on (dropping) until the client's own closing frame, so the
        connection ends cleanly and the client reads the code; a client that floods on is cut off."""
        if self._closing_since is None:
            self._closing_since = time.monotonic()
            self.close_reason, self.close_message = CLOSE_TOO_MANY_MESSAGES, reason
            self.on_overflow()
            try:
                self.sock.send(self.ws.send(CloseConnection(CLOSE_TOO_MANY_MESSAGES, reason)))
            except LocalProtocolError:
                return False
            self.event.set()
        return time.monotonic() - self._closing_since < CLOSE_HANDSHAKE_WAIT_S

    def _raise_if_overflowed(self) -> None:
        if self.inbound.overflow is not None:
            raise ConnectionClosed(CLOSE_TOO_MANY_MESSAGES, self.inbound.overflow)

    def _raise_if_logged_out(self) -> None:
        if time.monotonic() - self._login_checked_at < LOGIN_RECHECK_S:
            return
        self._login_checked_at = time.monotonic()
        if not self.login_still_open():
            message = "Your session has ended. Log in again."
            with contextlib.suppress(ConnectionClosed, LocalProtocolError, OSError):
                send_json(self, {"type": "error", "code": "not_logged_in", "message": message, "field": None})
                super().close(CLOSE_NOT_LOGGED_IN, message)
            raise ConnectionClosed(CLOSE_NOT_LOGGED_IN, message)

    def _raise_if_draining(self) -> None:
        if _draining.is_set():
            message = "The server is restarting; reconnecting."
            with contextlib.suppress(ConnectionClosed, LocalProtocolError, OSError):
                super().close(CLOSE_SERVICE_RESTART, message)
            raise ConnectionClosed(CLOSE_SERVICE_RESTART, message)

    def receive(self, timeout: float | None = None) -> str | bytes | None:
        """The next message (None after timeout s); ConnectionClosed once closed and nothing is left."""
        self._raise_if_overflowed()
        self._raise_if_draining()
        self._raise_if_logged_out()
        while self.connected and not self.inbound:
            if not self.event.wait(timeout=timeout):
                return None
            self.event.clear()
            self._raise_if_overflowed()
            self._raise_if_draining()
        message = self.inbound.pop()
        if message is None:
            raise ConnectionClosed(self.close_reason, self.close_message)
        return message

    def send(self, data: str | bytes) -> None:
        """Sends data; ConnectionClosed once the socket is closing."""
        self._raise_if_overflowed()
        self._raise_if_draining()
        self._raise_if_logged_out()
        try:
            super().send(data)
        except LocalProtocolError:  # the reader thread closed it meanwhile
            raise ConnectionClosed(self.close_reason, self.close_message) from None

    def close(self, reason: int | None = None, message: str | None = None) -> None:
        """Closes with reason and message; ConnectionClosed when it is already closing."""
        self._raise_if_overflowed()
        try:
            super().close(reason, message)
        except LocalProtocolError:
            raise ConnectionClosed(self.close_reason, self.close_message) from None


class FloodMemory:
    """Which users were closed for flooding which channel lately (this process's memory: each process protects
    itself); they are refused there until FLOOD_COOL_DOWN_S has passed."""

    def __init__(self) -> None:
        self._until: dict[tuple[str, int], float] = {}
        self._lock = threading.Lock()

    def remember(self, channel: str, user_id: int) -> None:
        """user_id flooded channel just now."""
        now = time.monotonic()
        with self._lock:
            self._until = {key: until for key, until in self._until.items() if until > now}
            self._until[(channel, user_id)] = now + FLOOD_COOL_DOWN_S

    def wait_s(self, channel: str, user_id: int) -> float:
        """Seconds before user_id may open channel again (0: now)."""
        return max(0.0, self._until.get((channel, user_id), 0.0) - time.monotonic())


class SocketCount:
    """How many sockets each user has open in this process."""

    def __init__(self) -> None:
        self._open: dict[int, int] = {}
        self._lock = threading.Lock()

    def open(self, user_id: int) -> bool:
        """Counts a new socket of user_id; False (nothing counted) when they are at MAX_SOCKETS_PER_USER."""
        with self._lock:
            if self._open.get(user_id, 0) >= MAX_SOCKETS_PER_USER:
                return False
            self._open[user_id] = self._open.get(user_id, 0) + 1
            return True

    def close(self, user_id: int) -> None:
        """A socket of user_id ended."""
        with self._lock:
            left = self._open.get(user_id, 0) - 1
            if left > 0:
                self._open[user_id] = left
            else:
                self._open.pop(user_id, None)


class _ChannelEnded(Response):
    """What the WSGI server gets once a channel's handler returned, per server (as flask-sock answers)."""

    def __init__(self, mode: str) -> None:
        super().__init__()
        self.mode = mode

    def __call__(self, environ: Any, start_response: Any) -> Any:
        if self.mode == "gunicorn":
            raise StopIteration()
        if self.mode == "werkzeug":
            return super().__call__(environ, start_response)
        return []


class Channels(Sock):
    """flask-sock's extension, with every channel opened one way: a ChannelSocket, then `open_channel`'s checks
    (logged in, same Origin), and only then the area's handler. A channel cannot skip them."""

    def __init__(self, app: Flask | None = None, login_still_open: Callable[[int], bool] = lambda _user_id: True
                 ) -> None:
        self.floods = FloodMemory()
        self.sockets = SocketCount()
        self.login_still_open = login_still_open
        super().__init__(app)

    def route(self, path: str, bp: Any = None, *, messages_per_s: int = DEFAULT_MESSAGES_PER_S,
              **kwargs: Any) -> Callable[[Callable[..., None]], None]:
        """Declares a channel at path; messages_per_s bounds what its clients may send."""

        def decorator(handler: Callable[..., None]) -> None:
            @wraps(handler)
            def channel(*args: Any, **values: Any) -> Response:
                # No permessage-deflate: a 4 kB compressed frame inflates to megabytes before any size check
                # sees it, and what we send (JSON, JPEG) gains little from it.
                request.environ.pop("HTTP_SEC_WEBSOCKET_EXTENSIONS", None)
                counted = int(current_user.get_id()) if current_user.is_authenticated else None
                if counted is not None and not self.sockets.open(counted):
                    raise ApiError(429, "too_many_sockets", f"You have {MAX_SOCKETS_PER_USER} connections open "
                                                            "already; close some of your lab tabs.")
                try:
                    ws = ChannelSocket(request.environ, messages_per_s, **current_app.config["SOCK_SERVER_OPTIONS"])
                    with contextlib.suppress(ConnectionClosed):
                        if open_channel(ws):
                            user_id = int(current_user.get_id())
                            ws.on_overflow = lambda: self.floods.remember(path, user_id)
                            ws.login_still_open = lambda: self._still_open(user_id)
                            if ws.inbound.overflow is not None:  # it flooded during the checks
                                ws.on_overflow()
                            handler(ws, *args, **values)
                    with contextlib.suppress(ConnectionClosed, LocalProtocolError, OSError):
                        ws.close()
                finally:
                    if counted is not None:
                        self.sockets.close(counted)
                request.environ[WEBSOCKET_ENDED] = True
                return _ChannelEnded(ws.mode)

            (bp or self.app).route(path, websocket=True, **kwargs)(channel)

        return decorator

    def _still_open(self, user_id: int) -> bool:
        try:
            return self.login_still_open(user_id)
        finally:
            get_session().close()  # the socket lives on; the check's database connection goes back

    def refuse_while_cooling_down(self) -> None:
        """ApiError 429 for a user closed for flooding this channel lately: refused before the handshake, a
        reconnecting flood costs no socket, no thread and no handler."""
        rule = request.url_rule
        if rule is None or not rule.websocket or not current_user.is_authenticated:
            return
        wait_s = self.floods.wait_s(rule.rule, int(current_user.get_id()))
        if wait_s > 0:
            raise ApiError(429, "too_many_messages",
                           f"This channel was closed for too many messages; try again in {math.ceil(wait_s)} s.")


ChannelDeclarations = Callable[[Channels], None]


def init_app(app: Flask, channels: Iterable[ChannelDeclarations],
             login_still_open: Callable[[int], bool] = lambda _user_id: True) -> Channels:
    """Binds the WebSocket extension to app and declares each area's channels on it; incoming messages are
    small and few, and idle sockets are pinged. login_still_open(user_id) says whether the login that opened
    a socket still holds (asked every LOGIN_RECHECK_S)."""
    app.config.setdefault("SOCK_SERVER_OPTIONS", {"ping_interval": PING_INTERVAL_S,
                                                  "max_message_size": MAX_MESSAGE_BYTES})
    sock = Channels(app, login_still_open)
    for declare in channels:
        declare(sock)

    @app.before_request
    def _websocket_only() -> None:
        if request.path.startswith("/ws/") and request.headers.get("Upgrade", "").lower() != "websocket":
            raise ApiError(400, "websocket_required", "This address takes WebSocket connections only.")
        sock.refuse_while_cooling_down()

    return sock


def send_json(ws: WebSocket, message: dict[str, object]) -> None:
    """Sends message as compact JSON text."""
    ws.send(json.dumps(message, separators=(",", ":")))


def refuse(ws: WebSocket, close_code: int, code: str, message: str, field: str | None = None) -> None:
    """Sends an error message naming code and field, then closes the socket with close_code."""
    send_json(ws, {"type": "error", "code": code, "message": message, "field": field})
    ws.close(reason=close_code, message=message[:120])
    # Wait for the client's closing frame: a socket torn down with it unread is reset, and the reset
    # can discard our error message before the client reads it.
    ws.thread.join(CLOSE_HANDSHAKE_WAIT_S)


def same_origin() -> bool:
    """Whether the handshake came from one of our own pages (or from a non-browser client)."""
    origin = request.headers.get("Origin")
    # Browsers always send Origin on WebSockets; its absence means a non-browser client, not a hijack.
    return origin is None or urlsplit(origin).netloc == request.host


def open_channel(ws: WebSocket) -> bool:
    """The checks every channel makes first (logged in, same origin); False once the socket is refused.
    `Channels.route` makes them before any handler runs."""
    if not current_user.is_authenticated:
        refuse(ws, CLOSE_NOT_LOGGED_IN, "not_logged_in", "Your session has ended. Log in again.")
        return False
    # A socket lives for hours: release the database connection the login check used.
    get_session().close()
    if not same_origin():
        refuse(ws, CLOSE_FORBIDDEN, "forbidden_origin", "This page may not open this channel.")
        return False
    return True


def relay_stream(ws: WebSocket, hub: FanoutHub, choose: Callable[[Any], Any] | None = None,
                 delay: ViewerDelay | None = None) -> None:
    """Sends the hub's newest message whenever there is one, and status changes, until the socket closes.

    choose picks this viewer's version of a message packed in several versions (e.g. with or without
    the ground truth). delay, when given, holds each message until its capture time + the viewer's injected
    delay (middleware/lab/delay.py); a change of delay is announced as {"type": "status", "injected_delay_s"}.
    """
    subscription = hub.subscribe()
    held = DelayQueue(0.0)
    try:
        # A closed hub returns at once: looping on it would spin a core until the viewer leaves.
        while ws.connected and not hub.closed:
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
        if hub.closed:
            ws.close(CLOSE_GOING_AWAY, "The lab is shutting down; reload the page in a moment.")
    except (ConnectionClosed, OSError):
        pass  # the viewer went (a closed tab mid-send): the end of this stream, not an error to log
    finally:
        subscription.close()


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


def pong(ping_id: int, measure_round_trip_ms: Callable[[], float | None]) -> dict[str, object]:
    """The answer to a ping, with a fresh round trip to whatever lies behind the channel (None: not reachable)."""
    robot_rtt_ms = measure_round_trip_ms()
    return {"type": "pong", "id": ping_id, "robot_rtt_ms": None if robot_rtt_ms is None else round(robot_rtt_ms, 3)}
