"""A WebSocket after its handshake, in two forms: `PendingSocket` (blocking, in the request's thread, while the
channel's checks run and may refuse it) and `LiveSocket` (on the channel loop, for the channel's life).

Frames are wsproto's; the rules are the ones every channel had with simple_websocket: a bounded inbound queue
(InboundQueue) closed with CLOSE_TOO_MANY_MESSAGES past its limits, messages of at most max_message_bytes, a
ping every ping_interval_s and a close when the client did not answer the previous one, and the login checked
again every LOGIN_RECHECK_S.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import logging
import socket
import time
from collections.abc import Awaitable, Callable
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from simple_websocket import ConnectionClosed
from wsproto.connection import Connection, ConnectionType
from wsproto.events import BytesMessage, CloseConnection, Message, Ping, TextMessage
from wsproto.frame_protocol import CloseReason
from wsproto.utilities import LocalProtocolError, generate_accept_token

from middleware.errors import ApiError
from middleware.live.codes import CLOSE_NOT_LOGGED_IN, CLOSE_TOO_MANY_MESSAGES

CLOSE_HANDSHAKE_WAIT_S = 1.0
# Past this many unsent bytes a stream's newest message is skipped (latest wins); past the hard limit the
# client has stopped reading and is closed.
STREAM_BUFFER_BYTES = 256 * 1024
STALLED_BUFFER_BYTES = 4 * 1024 * 1024
READ_BYTES = 65536
log = logging.getLogger(__name__)


def accept_websocket(environ: dict) -> socket.socket:
    """Answers the handshake (101) on the WSGI server's socket and returns that socket; ApiError 400 for a request
    that is not a WebSocket handshake this server can take over."""
    key = environ.get("HTTP_SEC_WEBSOCKET_KEY", "")
    raw = environ.get("gunicorn.socket") or environ.get("werkzeug.socket")
    if not _is_handshake_key(key) or environ.get("HTTP_SEC_WEBSOCKET_VERSION") != "13" or raw is None:
        raise ApiError(400, "websocket_required", gettext("This address takes WebSocket connections (version 13) "
                                                          "only."), "Sec-WebSocket-Key")
    raw.sendall(b"HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                b"Sec-WebSocket-Accept: " + generate_accept_token(key.encode("ascii")) + b"\r\n\r\n")
    return raw


def _is_handshake_key(key: str) -> bool:
    try:
        return len(base64.b64decode(key.encode("ascii"), validate=True)) == 16
    except (ValueError, UnicodeEncodeError):
        return False


async def wait_at_most(event: asyncio.Event, timeout: float | None) -> None:
    """Waits until event is set or timeout s passed (then it is set: callers clear it). asyncio.wait_for makes a
    task per wait, which at a thousand sockets' refreshes a second was the loop's largest cost."""
    if timeout is None:
        await event.wait()
        return
    timer = asyncio.get_running_loop().call_later(timeout, event.set)
    try:
        await event.wait()
    finally:
        timer.cancel()


def _log_failure(task: asyncio.Task) -> None:
    """A socket's own task (reader, pinger, login check) that failed is logged: silently, the socket would stop
    checking its login or answering pings."""
    if task.cancelled():
        return
    error = task.exception()
    if error is not None and not isinstance(error, ConnectionClosed):  # closed: the process is ending
        log.error("a socket's task failed", exc_info=error)


class PendingSocket:
    """The accepted socket while the request's thread checks who opened it: blocking sends, and a close."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self._frames = Connection(ConnectionType.SERVER)
        self.connected = True

    def send(self, data: str | bytes) -> None:
        if not self.connected:
            raise ConnectionClosed(CloseReason.NORMAL_CLOSURE, "")
        message = TextMessage(data) if isinstance(data, str) else BytesMessage(data)
        try:
            self.sock.sendall(self._frames.send(message))
        except OSError:
            self.connected = False
            raise ConnectionClosed(CloseReason.ABNORMAL_CLOSURE, "") from None

    def close(self, reason: int | None = None, message: str | None = None) -> None:
        """Sends the closing frame, then lingers until the client closes (or a second passes)."""
        if not self.connected:
            raise ConnectionClosed(CloseReason.NORMAL_CLOSURE, "")
        self.connected = False
        with contextlib.suppress(OSError, LocalProtocolError):
            self.sock.sendall(self._frames.send(CloseConnection(reason or CloseReason.NORMAL_CLOSURE, message)))
            self.sock.shutdown(socket.SHUT_WR)
            self.sock.settimeout(CLOSE_HANDSHAKE_WAIT_S)
            while self.sock.recv(4096):
                pass


class Inbox:
    """A channel's admitted messages and the wait for them, for a socket (LiveSocket) or a channel carried on one
    (live.link.SubSocket). Subclasses set connected, close_reason and close_message, and close()."""

    inbound: Any  # realtime.InboundQueue: admitted messages, or why the client overflowed
    connected: bool
    close_reason: int
    close_message: str
    on_overflow: Callable[[], None]

    def __init__(self, inbound: Any) -> None:
        self.inbound = inbound
        self._arrived = asyncio.Event()
        self.on_overflow = lambda: None
        self.handling = False  # a message was taken and its handler has not asked for the next one yet
        self.carried: set[Inbox] = set()  # the channels carried on this socket (a link's)

    def quiet(self) -> bool:
        """Nothing admitted waits and no handler holds a message, here or on a channel carried here: closing now
        loses no message the server has read (a leaving worker closes each socket once it is quiet)."""
        return not self.handling and not len(self.inbound) and all(c.quiet() for c in list(self.carried))

    def begin_close(self, reason: int, message: str) -> None:
        """Closes with reason at once (what follows may wait): receive and send raise from now on."""
        raise NotImplementedError

    async def close(self, reason: int | None = None, message: str | None = None) -> None:
        raise NotImplementedError

    async def _closed_for_overflow(self) -> None:
        """What follows begin_close after a flood (a socket waits for its client's closing frame)."""

    async def receive(self, timeout: float | None = None) -> str | bytes | None:
        """The next message, or None after timeout s or when nudged; ConnectionClosed once closed and nothing is
        left."""
        self.handling = False
        self._raise_if_overflowed()
        if not len(self.inbound):
            if not self.connected:
                raise ConnectionClosed(self.close_reason, self.close_message)
            if timeout is not None and timeout <= 0:
                return None
            await wait_at_most(self._arrived, timeout)  # set already: something came since the last receive
            self._arrived.clear()
            self._raise_if_overflowed()
            if not len(self.inbound):
                if not self.connected:
                    raise ConnectionClosed(self.close_reason, self.close_message)
                return None
        message = self.inbound.pop()
        self.handling = True
        return message

    def nudge(self) -> None:
        """Ends a receive that waits (it returns None): something else needs the channel's attention. On the loop."""
        self._arrived.set()

    def _raise_if_overflowed(self) -> None:
        if self.inbound.overflow is not None:
            raise ConnectionClosed(self.close_reason, self.inbound.overflow)

    def _admit(self, message: str | bytes) -> None:
        self.inbound.append(message)
        if self.inbound.overflow is not None:
            self.on_overflow()
            self.begin_close(CLOSE_TOO_MANY_MESSAGES, self.inbound.overflow)
            asyncio.ensure_future(self._closed_for_overflow())
        self._arrived.set()


class LiveSocket(Inbox):
    """A WebSocket served on the channel loop. receive/send raise ConnectionClosed once it is closed."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, inbound,
                 max_message_bytes: int, ping_interval_s: float) -> None:
        self._reader, self._writer = reader, writer
        super().__init__(inbound)
        self._frames = Connection(ConnectionType.SERVER)
        self._max_message_bytes = max_message_bytes
        self._ping_interval_s = ping_interval_s
        self._partial: list[str | bytes] = []
        self._partial_size = 0
        self.heard_at = time.monotonic()
        self.connected = True
        self.close_reason: int = CloseReason.NO_STATUS_RCVD
        self.close_message = ""
        self._closed = asyncio.Event()
        self._recheck = asyncio.Event()
        self._tasks: list[asyncio.Task] = []

    def start(self, login_still_open: Callable[[], Awaitable[bool]], login_recheck_s: Callable[[], float]) -> None:
        """Starts reading frames, pinging, and checking the login."""
        self._tasks = [asyncio.ensure_future(self._read_forever()), asyncio.ensure_future(self._ping_forever()),
                       asyncio.ensure_future(self._check_login_forever(login_still_open, login_recheck_s))]
        for task in self._tasks:
            task.add_done_callback(_log_failure)

    def silent_s(self) -> float:
        """Seconds since the client was last heard (any frame)."""
        return time.monotonic() - self.heard_at

    async def send(self, data: str | bytes) -> None:
        """Sends data, waiting while the client reads slower than we write."""
        self.write(data)
        if self._writer.transport.get_write_buffer_size() > STREAM_BUFFER_BYTES:
            with contextlib.suppress(ConnectionError):
                await self._writer.drain()

    def send_latest(self, data: str | bytes) -> bool:
        """Sends a stream's newest message unless the client is still behind on earlier ones; whether sent."""
        buffered = self._writer.transport.get_write_buffer_size()
        if buffered > STALLED_BUFFER_BYTES:
            self.abort("The client stopped reading.")
        if buffered > STREAM_BUFFER_BYTES:
            return False
        self.write(data)
        return True

    def write(self, data: str | bytes) -> None:
        """Queues data's frame for the client; ConnectionClosed when closed."""
        self._raise_if_overflowed()
        if not self.connected:
            raise ConnectionClosed(self.close_reason, self.close_message)
        message = TextMessage(data) if isinstance(data, str) else BytesMessage(data)
        try:
            self._writer.write(self._frames.send(message))
        except (LocalProtocolError, RuntimeError):
            raise ConnectionClosed(self.close_reason, self.close_message) from None

    def begin_close(self, reason: int, message: str) -> None:
        if self.connected:
            self.connected = False
            self.close_reason, self.close_message = reason, message
            with contextlib.suppress(LocalProtocolError, RuntimeError, ConnectionError):
                self._writer.write(self._frames.send(CloseConnection(reason, message)))
            self._arrived.set()

    async def close(self, reason: int | None = None, message: str | None = None) -> None:
        """Closes with reason and message, waits briefly for the client's answer, then drops the connection."""
        self.begin_close(reason or CloseReason.NORMAL_CLOSURE, message or "")
        await self._closed_for_overflow()

    async def _closed_for_overflow(self) -> None:
        # Reads on (dropping) until the client's closing frame, so it reads our code; then the connection goes.
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._closed.wait(), CLOSE_HANDSHAKE_WAIT_S)
        self.abort()

    def abort(self, why: str = "") -> None:
        """Drops the connection now."""
        if self.connected:
            self.connected = False
            self.close_reason, self.close_message = CloseReason.ABNORMAL_CLOSURE, why
        self._arrived.set()
        self._closed.set()
        for task in self._tasks:
            if task is not asyncio.current_task():
                task.cancel()
        self._writer.transport.abort() if why else self._writer.close()

    async def _read_forever(self) -> None:
        try:
            while True:
                data = await self._reader.read(READ_BYTES)
                if not data:
                    break
                self.heard_at = time.monotonic()
                self._frames.receive_data(data)
                for event in self._frames.events():
                    if not await self._handle(event):
                        return
        except (ConnectionError, LocalProtocolError, OSError):
            pass
        finally:
            self._closed.set()
            if self.connected:
                self.abort("The client went away.")

    async def _handle(self, event: object) -> bool:
        if isinstance(event, Message):
            self._partial_size += len(event.data)
            if self._partial_size > self._max_message_bytes:
                await self.close(CloseReason.MESSAGE_TOO_BIG, "Message too big")
                return False
            self._partial.append(event.data)
            if event.message_finished:
                joined = ("" if isinstance(event, TextMessage) else b"").join(self._partial)  # type: ignore[arg-type]
                self._partial, self._partial_size = [], 0
                if self.connected and self.inbound.overflow is None:
                    self._admit(joined)
        elif isinstance(event, Ping):
            with contextlib.suppress(LocalProtocolError):
                self._writer.write(self._frames.send(event.response()))
        elif isinstance(event, CloseConnection):
            if self.connected:
                self.connected = False
                self.close_reason, self.close_message = event.code, event.reason or ""
                with contextlib.suppress(LocalProtocolError, RuntimeError):
                    self._writer.write(self._frames.send(event.response()))
            self._arrived.set()
            self._closed.set()
            self._writer.close()
            return False
        return True  # a Pong: heard, nothing else to do

    async def _ping_forever(self) -> None:
        pinged_at = None
        while self.connected:
            await asyncio.sleep(self._ping_interval_s)
            if pinged_at is not None and self.heard_at < pinged_at:
                await self.close(CloseReason.POLICY_VIOLATION, "Ping timeout")
                return
            pinged_at = time.monotonic()
            with contextlib.suppress(LocalProtocolError, RuntimeError):
                self._writer.write(self._frames.send(Ping()))

    def recheck_login(self) -> None:
        """Checks the login now (a login of the user ended somewhere). On the loop."""
        self._recheck.set()

    async def _check_login_forever(self, login_still_open: Callable[[], Awaitable[bool]],
                                   every_s: Callable[[], float]) -> None:
        while self.connected:
            await wait_at_most(self._recheck, every_s())
            self._recheck.clear()
            if self.connected and not await login_still_open():
                message = gettext("Your session has ended. Log in again.")
                with contextlib.suppress(ConnectionClosed):
                    self.write(json.dumps({"type": "error", "code": "not_logged_in", "message": message,
                                           "field": None}, separators=(",", ":")))
                await self.close(CLOSE_NOT_LOGGED_IN, message)
                return
