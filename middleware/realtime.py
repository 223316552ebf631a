"""The WebSocket extension and the plumbing every channel shares: bounded inbound messages, the login and
Origin checks, close codes, refuse(), relaying a fanned-out stream, ping/pong.

Each area declares its channels in its own `sockets.py` with a `register(sock)` function; `create_app`
calls them, so no channel exists by the side effect of an import. Every channel declared through
`Channels.route` gets a `ChannelSocket` and the checks of `open_channel` before its handler runs.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import functools
import json
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from functools import wraps
from typing import Any, Protocol
from urllib.parse import urlsplit

from flask import Flask, Response, current_app, request
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from flask_sock import Sock
from simple_websocket import ConnectionClosed
from werkzeug.exceptions import NotFound

from middleware import events
from middleware.auth.session_records import ACCOUNTS_TOPIC, forget_verdicts
from middleware.db import get_session, session_factory
from middleware.errors import ApiError
from middleware.live.codes import (  # noqa: F401 - the channels import the codes from here
    CLOSE_FORBIDDEN,
    CLOSE_GOING_AWAY,
    CLOSE_NOT_FOUND,
    CLOSE_NOT_LOGGED_IN,
    CLOSE_SERVICE_RESTART,
    CLOSE_TOO_MANY_MESSAGES,
    CLOSE_TRY_AGAIN_LATER,
)
from middleware.live.link import LINK_PATH, CoolingDown, Declared, Link, RecordingSocket
from middleware.live.loop import Continuation, channel_loop, recheck_logins
from middleware.live.wire import LiveSocket, PendingSocket, accept_websocket, wait_at_most
from middleware.robots.fanout import FanoutHub
from middleware.validation import TolerantResponse, check_path_arguments, decimal_int

STREAM_POLL_S = 0.5
# A live client answers each ping, so it is heard at least this often; one that does not answer by the next
# ping is closed (simple_websocket's rule), and a seat counts its grace from when its client was last heard.
PING_INTERVAL_S = 5.0
# A socket outlives the request that opened it: a logout, a password change or a disabled account is announced
# and closes the user's sockets (CLOSE_NOT_LOGGED_IN) in every worker at once; besides, the login is checked every
# LOGIN_RECHECK_QUIET_S (its idle timeout and lifetime), or every LOGIN_RECHECK_S while announcements go unheard.
LOGIN_RECHECK_S = 5.0
LOGIN_RECHECK_QUIET_S = 60.0
MAX_MESSAGE_BYTES = 4096
# Channels take a person's actions (a click, a chat line) and pings; the drive channel declares more.
DEFAULT_MESSAGES_PER_S = 10
# A link carries a page's channels: the drive channel's 50 a second and the others' few.
LINK_MESSAGES_PER_S = 80
# Open sockets per user in one process: a console tab holds one link (`/ws/link`), so many tabs fit. An open socket
# costs no thread (live/loop.py serves it) but its buffers, its pings and its login checks, and each handshake holds
# a request thread while its checks run, so a script opening thousands is refused (429) before the handshake.
MAX_SOCKETS_PER_USER = 40
# How long a user closed for flooding a channel is refused on it: reconnecting buys no fresh allowance.
FLOOD_COOL_DOWN_S = 10.0

# Set in the WSGI environ once a request was served as a WebSocket (serve.py then writes no HTTP answer).
WEBSOCKET_ENDED = "telelab.websocket_ended"

WebSocket = Any  # a PendingSocket while a channel opens (live.wire)
# Called in the request that opens a socket; what it returns says later, in the app's context, whether that
# request's login still holds for a user id.
LoginCheck = Callable[[], Callable[[int], bool]]


class InboundQueue:
    """The messages a channel received and has not handled yet: at most per_s a second are admitted (bursts
    included), and at most per_s wait. Past either, everything waiting is dropped and `overflow` says why: the
    socket is then closed, not left to queue work.

    The socket's reader on the channel loop appends (live.wire.Inbox); the channel's handler pops.
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


class _ChannelEnded(TolerantResponse):
    """What the WSGI server gets once a channel's handler returned, per server (as flask-sock answers). The app's
    own response class: Flask would otherwise recast it, and gunicorn would write a 200 after the handshake."""

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

    def __init__(self, app: Flask | None = None, login_check: LoginCheck = lambda: lambda _user_id: True) -> None:
        self.floods = FloodMemory()
        self.sockets = SocketCount()
        self.login_check = login_check
        self.declared: dict[str, Declared] = {}  # rule -> opener, for channels opened on a link
        super().__init__(app)

    def route(self, path: str, bp: Any = None, *, messages_per_s: int = DEFAULT_MESSAGES_PER_S,
              **kwargs: Any) -> Callable[[Callable[..., Continuation | None]], None]:
        """Declares a channel at path; messages_per_s bounds what its clients may send."""

        def decorator(handler: Callable[..., Continuation | None]) -> None:
            self.declared[path] = Declared(handler, messages_per_s)

            @wraps(handler)
            def channel(*args: Any, **values: Any) -> Response:
                # No permessage-deflate: a 4 kB compressed frame inflates to megabytes before any size check
                # sees it, and what we send (JSON, JPEG) gains little from it.
                request.environ.pop("HTTP_SEC_WEBSOCKET_EXTENSIONS", None)
                counted = int(current_user.get_id()) if current_user.is_authenticated else None
                if counted is not None and not self.sockets.open(counted):
                    raise ApiError(429, "too_many_sockets", gettext("You have %(count)s connections open already; "
                                                                    "close some of your lab tabs.",
                                                                    count=MAX_SOCKETS_PER_USER))
                served: concurrent.futures.Future[None] | None = None
                try:
                    raw = accept_websocket(request.environ)
                    ws = PendingSocket(raw)
                    continuation = None
                    with contextlib.suppress(ConnectionClosed):
                        if open_channel(ws):
                            continuation = handler(ws, *args, **values)
                    if continuation is not None:
                        served = self._adopt(raw, continuation, path, messages_per_s, counted)
                    else:
                        with contextlib.suppress(ConnectionClosed):
                            ws.close()
                finally:
                    if served is None and counted is not None:
                        self.sockets.close(counted)
                get_session().close()  # the request's database connection goes back before the socket lives on
                request.environ[WEBSOCKET_ENDED] = True
                return _ChannelEnded("gunicorn" if "gunicorn.socket" in request.environ else "werkzeug")

            (bp or self.app).route(path, websocket=True, **kwargs)(channel)

        return decorator

    def _adopt(self, raw: Any, continuation: Continuation, path: str, messages_per_s: int,
               user_id: int | None) -> concurrent.futures.Future[None]:
        """Hands the accepted socket to the process's channel loop."""
        assert user_id is not None  # open_channel refused everyone else
        options = current_app.config["SOCK_SERVER_OPTIONS"]
        return channel_loop().adopt(
            raw, continuation, app=current_app._get_current_object(),  # type: ignore[attr-defined]
            inbound=InboundQueue(messages_per_s), max_message_bytes=options["max_message_size"],
            ping_interval_s=options["ping_interval"], login_recheck_s=self._login_recheck_s, user_id=user_id,
            login_still_open=functools.partial(self._still_open, self.login_check(), user_id),
            on_overflow=lambda: self.floods.remember(path, user_id),
            on_end=lambda: self.sockets.close(user_id))

    def link_channel(self, ws: WebSocket) -> Continuation:
        """/ws/link: every channel of a page on one socket (live/link.py). Each channel is opened later, on the
        pool, in a request made from this one's headers, with the same checks as its own socket."""
        app = current_app._get_current_object()  # type: ignore[attr-defined]
        user_id = int(current_user.get_id())
        headers = {name: value for name, value in request.headers.items()
                   if name.lower() in {"cookie", "origin", "host", "user-agent", "x-forwarded-for",
                                       "x-forwarded-proto"}}
        headers.update({"Upgrade": "websocket", "Connection": "Upgrade"})
        environ_base = {"REMOTE_ADDR": request.remote_addr or "", "wsgi.url_scheme": request.scheme}
        loop = channel_loop()

        def open_in_request(path: str) -> tuple[str, Declared, Continuation | None, RecordingSocket]:
            with app.test_request_context(path, base_url=request_base, headers=headers, environ_base=environ_base):
                rule = request.url_rule
                if rule is None or rule.rule == LINK_PATH or rule.rule not in self.declared:
                    raise NotFound()
                check_path_arguments(request.view_args)  # as before_request does for a socket of its own
                wait_s = self.floods.wait_s(rule.rule, user_id)
                if wait_s > 0:
                    raise CoolingDown("This channel was closed for too many messages; try again in "
                                      f"{math.ceil(wait_s)} s.")
                declared = self.declared[rule.rule]
                opening = RecordingSocket()
                continuation = None
                try:
                    with contextlib.suppress(ConnectionClosed):
                        if open_channel(opening):
                            continuation = declared.opener(opening, **(request.view_args or {}))
                finally:
                    get_session().close()
                return rule.rule, declared, continuation, opening

        request_base = request.host_url

        async def serve(live: LiveSocket) -> None:
            link = Link(live, app, lambda path: loop.work(app, open_in_request, path), InboundQueue,
                        lambda rule: self.floods.remember(rule, user_id))
            await link.serve()

        return serve

    def _login_recheck_s(self) -> float:
        # Ended logins are announced (session_records.ACCOUNTS_TOPIC): while this process hears announcements a
        # socket checks its login when told and otherwise rarely (idle timeouts); else every LOGIN_RECHECK_S.
        bus = events.bus_of(session_factory(self.app).kw["bind"])
        return LOGIN_RECHECK_QUIET_S if not bus.shared or bus.listening.is_set() else LOGIN_RECHECK_S

    def _still_open(self, still_open: Callable[[int], bool], user_id: int) -> bool:
        try:
            return still_open(user_id)
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
                           gettext("This channel was closed for too many messages; try again in %(seconds)s s.",
                                   seconds=math.ceil(wait_s)))


ChannelDeclarations = Callable[[Channels], None]


def init_app(app: Flask, channels: Iterable[ChannelDeclarations],
             login_check: LoginCheck = lambda: lambda _user_id: True) -> Channels:
    """Binds the WebSocket extension to app and declares each area's channels on it; incoming messages are
    small and few, and idle sockets are pinged. login_check(), called in the request that opens a socket, says
    later whether that login still holds (asked when a login of the user ends, and every LOGIN_RECHECK_QUIET_S)."""
    app.config.setdefault("SOCK_SERVER_OPTIONS", {"ping_interval": PING_INTERVAL_S,
                                                  "max_message_size": MAX_MESSAGE_BYTES})
    sock = Channels(app, login_check)
    for declare in channels:
        declare(sock)
    sock.route(LINK_PATH, messages_per_s=LINK_MESSAGES_PER_S, endpoint="link_channel")(sock.link_channel)
    events.listen(session_factory(app).kw["bind"], ACCOUNTS_TOPIC, _logins_ended)

    @app.before_request
    def _websocket_only() -> None:
        if request.path.startswith("/ws/") and request.headers.get("Upgrade", "").lower() != "websocket":
            raise ApiError(400, "websocket_required", gettext("This address takes WebSocket connections only."))
        sock.refuse_while_cooling_down()

    return sock


class ViewerHold(Protocol):
    """A viewer's hold on a robot's stream (the experiment's injected delay): messages kept back until their time."""

    def update(self, ws: Any, online: bool) -> bool:
        """Reads what is in force (a change is announced with ws.send); whether messages are held now."""

    def push(self, message: bytes | str, now_s: float) -> None:
        """Holds message until its time."""

    def pop_due(self, now_s: float) -> list[bytes | str]:
        """The held messages whose time has come, oldest first."""

    def seconds_until_next(self, now_s: float) -> float | None:
        """How long until the next release, or None when nothing is held."""


ViewerHolds = Callable[[str, int], ViewerHold]  # (robot name, user id) -> that viewer's hold on the robot's streams
_HOLDS_KEY = "telelab.viewer_holds"


def hold_viewers_with(app: Flask, holds: ViewerHolds) -> None:
    """Makes holds the hook every robot stream of app asks for its viewer's hold (composed in create_app)."""
    app.extensions[_HOLDS_KEY] = holds


def viewer_hold(robot_name: str, user_id: int) -> ViewerHold | None:
    """user_id's hold on robot_name's streams by the composed hook, or None when the app composed none."""
    holds: ViewerHolds | None = current_app.extensions.get(_HOLDS_KEY)
    return None if holds is None else holds(robot_name, user_id)


def _logins_ended(key: str | None) -> None:
    """A login of user key (None: anyone's) ended in some worker. This process's verdicts on it go first: kept up
    to RECHECK_S, a verdict from just before would let the next request in, and answer each socket's check yes."""
    user_id = decimal_int(key, 1) if key else None
    forget_verdicts(user_id)
    recheck_logins(user_id)


def as_json(message: dict[str, object]) -> str:
    """message as compact JSON text."""
    return json.dumps(message, separators=(",", ":"))


def send_json(ws: WebSocket, message: dict[str, object]) -> None:
    """Sends message as compact JSON text (on a socket still opening: a PendingSocket)."""
    ws.send(as_json(message))


def refuse(ws: WebSocket, close_code: int, code: str, message: str, field: str | None = None) -> None:
    """Sends an error message naming code and field, then closes the socket with close_code."""
    send_json(ws, {"type": "error", "code": code, "message": message, "field": field})
    ws.close(reason=close_code, message=message[:120])  # waits for the client's closing frame (see PendingSocket)


def same_origin() -> bool:
    """Whether the handshake came from one of our own pages (or from a non-browser client)."""
    origin = request.headers.get("Origin")
    # Browsers always send Origin on WebSockets; its absence means a non-browser client, not a hijack.
    return origin is None or urlsplit(origin).netloc == request.host


def open_channel(ws: WebSocket) -> bool:
    """The checks every channel makes first (logged in, same origin); False once the socket is refused.
    `Channels.route` makes them before any handler runs."""
    if not current_user.is_authenticated:
        refuse(ws, CLOSE_NOT_LOGGED_IN, "not_logged_in", gettext("Your session has ended. Log in again."))
        return False
    # A socket lives for hours: release the database connection the login check used.
    get_session().close()
    if not same_origin():
        refuse(ws, CLOSE_FORBIDDEN, "forbidden_origin", gettext("This page may not open this channel."))
        return False
    return True


async def relay_stream(ws: LiveSocket, hub: FanoutHub, choose: Callable[[Any], Any] | None = None,
                       hold: ViewerHold | None = None) -> None:
    """Sends the hub's newest message whenever there is one, and status changes, until the socket closes.

    choose picks this viewer's version of a message packed in several versions (e.g. with or without
    the ground truth). hold, when given, keeps messages back until their time (the viewer's injected delay, by
    the hook create_app composes: `viewer_hold`).
    A viewer that reads slower than the stream skips to the newest message.
    """
    watch = channel_loop().watch(hub)
    news = watch.join()
    subscription = hub.subscribe()
    announcer = _Announcer(ws)
    try:
        # A closed hub returns at once: looping on it would spin a core until the viewer leaves.
        while ws.connected and not hub.closed:
            news.clear()  # before reading: news from now on wakes the wait below
            status = subscription.status_change()
            if status is not None:
                await ws.send(json.dumps({"type": "status", "robot_online": status.online,
                                          "message": status.message}, separators=(",", ":")))
            holding = hold is not None and hold.update(announcer, hub.status_with_version()[0].online)
            message = subscription.next_message(0)
            if message is not None:
                message = message if choose is None else choose(message)
                if holding and hold is not None:
                    hold.push(message, time.time())
                else:
                    ws.send_latest(message)
            for due in hold.pop_due(time.time()) if hold is not None else ():
                ws.send_latest(due)
            while await ws.receive(timeout=0) is not None:
                pass  # nothing is expected from viewers; drop it so it cannot pile up
            if message is None:
                wait_s = hold.seconds_until_next(time.time()) if hold is not None else None
                await wait_at_most(news, STREAM_POLL_S if wait_s is None else min(wait_s, STREAM_POLL_S))
        if hub.closed:
            await ws.close(CLOSE_GOING_AWAY, "The lab is shutting down; reload the page in a moment.")
    finally:
        watch.leave(news)
        subscription.close()


class _Announcer:
    """What a hold announces on: the socket's non-waiting write."""

    def __init__(self, ws: LiveSocket) -> None:
        self.send = ws.write


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
