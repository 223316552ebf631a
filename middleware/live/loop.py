"""The channel loop: one asyncio event loop per process that serves every WebSocket of the process.

A channel is opened in the request's thread (its checks need the request: the login, the Origin, the robot),
then its socket is handed to this loop and the request's thread goes back to the server at once, so an open
socket costs a few kilobytes and no thread. Work that blocks (a database read, a robot's RPC) runs on a small
pool shared by all sockets, inside the app's context.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import functools
import logging
import os
import socket
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any

from flask import Flask, current_app
from simple_websocket import ConnectionClosed

from middleware.live.codes import CLOSE_GOING_AWAY, CLOSE_SERVER_FAILED, CLOSE_SERVICE_RESTART
from middleware.live.wire import LiveSocket

log = logging.getLogger(__name__)

DRAIN_WAIT_S = 10.0  # a leaving worker's socket closes once quiet, or after this anyway (within gunicorn's 15 s)
DRAIN_LOOK_S = 0.02
WORK_THREADS = 16  # blocking work of all sockets; the database pool (5 + 10 overflow) bounds it anyway
STREAM_READ_LIMIT = 256 * 1024

Continuation = Callable[[LiveSocket], Awaitable[None]]


class ChannelLoop:
    """This process's loop, its sockets and its pool for blocking work."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._pool = concurrent.futures.ThreadPoolExecutor(WORK_THREADS, thread_name_prefix="channel-work")
        self._sockets: set[LiveSocket] = set()
        self._by_user: dict[int, set[LiveSocket]] = {}
        self._watches: dict[int, StreamWatch] = {}
        self.draining = False
        self._thread = threading.Thread(target=self.loop.run_forever, name="channel-loop", daemon=True)
        self._thread.start()

    @property
    def open_sockets(self) -> int:
        return len(self._sockets)

    def adopt(self, raw: socket.socket, continuation: Continuation, *, app: Flask, inbound: Any,
              max_message_bytes: int, ping_interval_s: float, login_recheck_s: Callable[[], float],
              user_id: int, login_still_open: Callable[[], bool], on_overflow: Callable[[], None],
              on_end: Callable[[], None]) -> concurrent.futures.Future[None]:
        """Serves the accepted socket raw with continuation on this loop; the request's thread returns at once."""
        held = take_connection(raw)
        held.setblocking(False)

        async def serve() -> None:
            try:
                reader, writer = await asyncio.open_connection(sock=held, limit=STREAM_READ_LIMIT)
            except OSError:
                held.close()
                on_end()
                return
            ws = LiveSocket(reader, writer, inbound, max_message_bytes, ping_interval_s)
            ws.on_overflow = on_overflow
            ws.start(lambda: self.work(app, login_still_open), login_recheck_s)
            self._sockets.add(ws)
            self._by_user.setdefault(user_id, set()).add(ws)
            try:
                if self.draining:
                    await ws.close(CLOSE_SERVICE_RESTART, "The server is restarting; reconnecting.")
                    return
                await continuation(ws)
            except (ConnectionClosed, ConnectionError):
                pass  # the client went, or the socket was closed for a reason already sent
            except Exception:
                log.exception("a channel failed")
                with contextlib.suppress(Exception):
                    await ws.close(CLOSE_SERVER_FAILED, "The server failed on this channel; reload the page.")
            finally:
                self._sockets.discard(ws)
                self._by_user.get(user_id, set()).discard(ws)
                if not self._by_user.get(user_id, True):
                    del self._by_user[user_id]
                if ws.connected:
                    with contextlib.suppress(Exception):
                        await ws.close()
                ws.abort()
                on_end()

        return asyncio.run_coroutine_threadsafe(serve(), self.loop)

    async def work(self, app: Flask, fn: Callable[..., Any], *args: Any) -> Any:
        """fn(*args) on the pool, in app's context: for anything that blocks."""

        def call() -> Any:
            with app.app_context():
                return fn(*args)

        try:
            return await self.loop.run_in_executor(self._pool, call)
        except RuntimeError as error:  # the pool was shut down: the interpreter is exiting
            if "after shutdown" not in str(error):
                raise
            raise ConnectionClosed(CLOSE_GOING_AWAY, "The server is stopping.") from None

    def watch(self, hub: Any) -> StreamWatch:
        """The loop's watch of a FanoutHub (made once per hub); call on the loop."""
        watch = self._watches.get(id(hub))
        if watch is None or watch.hub is not hub:
            watch = self._watches[id(hub)] = StreamWatch(self.loop, hub)
        return watch

    def recheck_logins(self, user_id: int | None) -> None:
        """The sockets of user_id (None: everyone's) check their login now. From any thread."""
        def recheck() -> None:
            sockets = self._sockets if user_id is None else self._by_user.get(user_id, set())
            for ws in list(sockets):
                ws.recheck_login()

        with contextlib.suppress(RuntimeError):  # the loop closed: the process is ending
            self.loop.call_soon_threadsafe(recheck)

    def drain(self) -> None:
        """This worker is leaving: every socket closes with CLOSE_SERVICE_RESTART (its client reconnects to another
        worker) once the messages it has read are handled and answered, and new ones are closed at once. Safe from
        a signal handler."""
        if self.draining:
            return
        self.draining = True
        with contextlib.suppress(RuntimeError):  # the loop closed: the process is ending
            self.loop.call_soon_threadsafe(self._close_all)

    def wait_drained(self, timeout_s: float) -> bool:
        """Blocks until every socket of this process has closed (closing frames sent, their channels ended), at
        most timeout_s; whether they all did. For a leaving worker, before its process ends."""
        deadline = time.monotonic() + timeout_s
        while self._sockets and time.monotonic() < deadline:
            time.sleep(0.05)
        return not self._sockets

    def _close_all(self) -> None:
        for ws in list(self._sockets):
            asyncio.ensure_future(self._close_when_quiet(ws))

    async def _close_when_quiet(self, ws: LiveSocket) -> None:
        """Closes ws with CLOSE_SERVICE_RESTART once no message it read waits or is in a handler (at most
        DRAIN_WAIT_S): a chat line sent just before the restart is stored and answered first. No await comes
        between the last look and the closing frame, so nothing read in between goes unanswered."""
        deadline = self.loop.time() + DRAIN_WAIT_S
        while ws.connected and not ws.quiet() and self.loop.time() < deadline:
            await asyncio.sleep(DRAIN_LOOK_S)
        await ws.close(CLOSE_SERVICE_RESTART, "The server is restarting; reconnecting.")


def take_connection(raw: socket.socket) -> socket.socket:
    """The connection under raw, on a descriptor of our own. The WSGI server's descriptor then holds a stand-in
    whose peer is closed: what the server does when the request ends (gunicorn and Werkzeug shut the socket down,
    drain it, close it) happens to the stand-in at once, and the connection lives on."""
    held = raw.dup()
    stand_in, peer = socket.socketpair()
    peer.close()
    os.dup2(stand_in.fileno(), raw.fileno())
    stand_in.close()
    return held


class StreamWatch:
    """Wakes this loop's viewers of one FanoutHub when it has a new message or status: one hop per message from
    the hub's pump thread, however many viewers."""

    def __init__(self, loop: asyncio.AbstractEventLoop, hub: Any) -> None:
        self.hub = hub
        self._loop = loop
        self._viewers: set[asyncio.Event] = set()
        hub.listen(self._news)

    def _news(self) -> None:
        # The hub's pump runs on this loop, so its news wakes the viewers at once: a hop through
        # call_soon_threadsafe wrote the loop's self-pipe and woke its selector once per message per robot.
        if _running_loop() is self._loop:
            self._wake()
            return
        with contextlib.suppress(RuntimeError):  # the loop is closed: the process is ending
            self._loop.call_soon_threadsafe(self._wake)

    def _wake(self) -> None:
        for event in self._viewers:
            event.set()

    def join(self) -> asyncio.Event:
        event = asyncio.Event()
        self._viewers.add(event)
        return event

    def leave(self, event: asyncio.Event) -> None:
        self._viewers.discard(event)


def _running_loop() -> asyncio.AbstractEventLoop | None:
    """The loop running in this thread, or None (a thread with no loop: a hub closed from a request)."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


_loops: dict[int, ChannelLoop] = {}
_lock = threading.Lock()


def channel_loop() -> ChannelLoop:
    """This process's channel loop, started on first use (a forked worker starts its own)."""
    pid = os.getpid()
    with _lock:
        if pid not in _loops:
            _loops.clear()
            _loops[pid] = ChannelLoop()
        return _loops[pid]


def drain_channels() -> None:
    """Closes every socket of this process with CLOSE_SERVICE_RESTART once quiet (a worker leaving); returns at once
    (safe from a signal handler): wait_for_channels waits for it."""
    loop = _loops.get(os.getpid())
    if loop is not None:
        loop.drain()


def wait_for_channels(timeout_s: float) -> bool:
    """Drains this process's sockets and waits until they have all closed, at most timeout_s; whether they did."""
    loop = _loops.get(os.getpid())
    if loop is None:
        return True
    loop.drain()
    return loop.wait_drained(timeout_s)


def blocking_work() -> Callable[..., Awaitable[Any]]:
    """For a channel's continuation, made while the channel opens (in its request): `await work(fn, *args)` runs
    fn on the loop's pool in the request's app."""
    return functools.partial(channel_loop().work, current_app._get_current_object())  # type: ignore[attr-defined]


def recheck_logins(user_id: int | None) -> None:
    """This process's sockets of user_id (None: all) check their login now (a login ended, in any worker)."""
    loop = _loops.get(os.getpid())
    if loop is not None:
        loop.recheck_logins(user_id)
