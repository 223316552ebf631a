"""Latest-wins fan-out of one upstream stream to any number of viewers.

One pump per stream pulls from the robot while anyone watches, as a task on the process's asyncio loop (the channel
loop of live/loop.py, which serves every WebSocket): no thread per stream, so a worker's threads stay flat however
many robots its consoles watch. Each message is packed once, when a viewer first asks for it, and handed to every
viewer that asks: a message no viewer reads (a viewer that samples, as the class wall does, or reads the upstream's own
message with `next_item`) is never packed. A slow viewer skips to the newest message: it never slows the others and
never builds a backlog. Viewers on the loop wait with `listen`;
viewers on threads of their own (a recorder, the demo video) wait with `Subscription.next_message`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from middleware.live.loop import channel_loop

log = logging.getLogger(__name__)

Packed = TypeVar("Packed")


def _channel_event_loop() -> asyncio.AbstractEventLoop:
    return channel_loop().loop  # started on first use (a forked worker starts its own)


@dataclass(frozen=True)
class StreamStatus:
    """Whether the upstream is delivering, with a sentence for people when it is not."""

    online: bool
    message: str


class Subscription(Generic[Packed]):
    """One viewer's cursor into a hub: it sees the newest message it has not seen yet."""

    def __init__(self, hub: FanoutHub[Packed]) -> None:
        self._hub = hub
        self._seen_version = 0
        self._seen_status_version = 0

    def next_message(self, timeout_s: float) -> Packed | None:
        """The newest message not yet seen, waiting up to timeout_s; None when nothing new came."""
        message, self._seen_version = self._hub.wait_newer(self._seen_version, timeout_s)
        return message

    def next_item(self, timeout_s: float) -> object | None:
        """As next_message, but the upstream's message as it came (for a viewer that reads a few fields of it)."""
        item, self._seen_version = self._hub.wait_newer(self._seen_version, timeout_s, packed=False)
        return item

    def status_change(self) -> StreamStatus | None:
        """The upstream status if it changed since the last call."""
        status, version = self._hub.status_with_version()
        if version == self._seen_status_version:
            return None
        self._seen_status_version = version
        return status

    def close(self) -> None:
        """Stops watching; the hub stops its pump when the last viewer leaves."""
        self._hub.unsubscribe(self)


class FanoutHub(Generic[Packed]):
    """Pumps open_stream() while subscribed, packing each item once with pack().

    open_stream is called on the loop and returns an async iterator (a grpc.aio server-streaming call); cancel(stream)
    is called on the loop when the pump lets go of it. loop gives the loop the pump runs on (the channel loop)."""

    def __init__(
        self,
        name: str,
        open_stream: Callable[[], AsyncIterator[object]],
        pack: Callable[[Any], Packed],  # takes what open_stream yields
        cancel: Callable[[AsyncIterator[object]], None],
        backoff_s: tuple[float, float] = (0.2, 5.0),
        loop: Callable[[], asyncio.AbstractEventLoop] = _channel_event_loop,
    ) -> None:
        self.name = name
        self._open_stream = open_stream
        self._pack = pack
        self._cancel = cancel
        self._backoff_min_s, self._backoff_max_s = backoff_s
        self._lock = threading.Condition()
        self._subscribers: set[Subscription[Packed]] = set()
        self._latest_item: object | None = None  # the upstream's newest message, as it came
        self._version = 0
        self._latest: Packed | None = None  # it packed, once a viewer asked (for version _packed_version)
        self._packed_version = 0
        self._pack_failing = False
        self._status = StreamStatus(True, "connecting")
        self._status_version = 0
        self._loop = loop
        self._pumping: asyncio.AbstractEventLoop | None = None  # the loop a pump is scheduled or running on
        self._task: asyncio.Task[None] | None = None
        self._closed = False
        self._listeners: list[Callable[[], None]] = []
        self.messages_packed = 0

    def listen(self, news: Callable[[], None]) -> None:
        """Calls news() (on the pump's loop; it must not block) after every new message or status change and
        when the hub closes: how viewers that are not threads learn of them."""
        with self._lock:
            self._listeners.append(news)

    def _tell_listeners(self) -> None:
        for news in list(self._listeners):
            news()

    def subscribe(self) -> Subscription[Packed]:
        """A new viewer; starts the pump if it is the first."""
        subscription = Subscription(self)
        with self._lock:
            if self._closed:
                raise RuntimeError(f"{self.name} is closed")
            self._subscribers.add(subscription)
            if self._pumping is None:
                # What the hub holds is from when it last pumped (maybe minutes ago): the viewer waits for a new one.
                subscription._seen_version = self._version
                loop = self._pumping = self._loop()
                asyncio.run_coroutine_threadsafe(self._run(), loop)
        return subscription

    def unsubscribe(self, subscription: Subscription[Packed]) -> None:
        """Removes a viewer; the last one leaving cancels the upstream stream (from any thread)."""
        with self._lock:
            self._subscribers.discard(subscription)
            idle = not self._subscribers
        if idle:
            self._stop_pump()

    def _stop_pump(self) -> None:
        with self._lock:
            task, loop = self._task, self._pumping
        if task is not None and loop is not None:
            with contextlib.suppress(RuntimeError):  # the loop has stopped: the process is ending
                loop.call_soon_threadsafe(task.cancel)

    @property
    def viewer_count(self) -> int:
        """How many viewers are subscribed."""
        with self._lock:
            return len(self._subscribers)

    @property
    def closed(self) -> bool:
        """Whether the hub was closed (the application is shutting down)."""
        with self._lock:
            return self._closed

    def wait_newer(self, seen_version: int, timeout_s: float, packed: bool = True) -> tuple[Any, int]:
        """The latest message if newer than seen_version (waiting up to timeout_s), packed (or as it came), and its
        version."""
        deadline = time.monotonic() + timeout_s
        with self._lock:
            while self._version <= seen_version and not self._closed:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not self._lock.wait(remaining):
                    return None, seen_version
            if self._version <= seen_version:
                return None, seen_version
            return (self._packed_latest() if packed else self._latest_item), self._version

    def _packed_latest(self) -> Packed | None:
        """The newest message packed, packing it if no viewer has yet (under the lock: once per message)."""
        if self._packed_version != self._version:
            self._packed_version = self._version
            try:
                self._latest = self._pack(self._latest_item)
                self._pack_failing = False
            except Exception:  # noqa: BLE001 - a message that cannot be packed is skipped, the stream goes on
                if not self._pack_failing:  # once per run of failures, not at the stream's rate
                    log.exception("%s: a message could not be packed", self.name)
                self._pack_failing = True
                self._latest = None
            self.messages_packed += 1
        return self._latest

    def status_with_version(self) -> tuple[StreamStatus, int]:
        """The upstream status and a number that changes whenever it does."""
        with self._lock:
            return self._status, self._status_version

    @property
    def pumping(self) -> bool:
        """Whether a pump is scheduled or running (someone watches)."""
        with self._lock:
            return self._pumping is not None

    def close(self) -> None:
        """Stops the pump and wakes every viewer (application shutdown)."""
        with self._lock:
            self._closed = True
            self._lock.notify_all()
        self._tell_listeners()
        self._stop_pump()

    def _set_status(self, status: StreamStatus) -> None:
        with self._lock:
            if status == self._status:
                return
            self._status = status
            self._status_version += 1
            self._lock.notify_all()
        self._tell_listeners()

    def _wanted(self) -> bool:
        with self._lock:
            return bool(self._subscribers) and not self._closed

    async def _run(self) -> None:
        """The pump: reads the upstream while anyone watches, reconnecting with a backoff while the robot is away.
        Cancelled (on its loop) when the last viewer leaves or the hub closes."""
        with self._lock:
            self._task = asyncio.current_task()
        try:
            await self._pump_while_wanted()
        except asyncio.CancelledError:
            pass  # the last viewer left, or the hub closed
        finally:
            with self._lock:
                self._task = None
                again = bool(self._subscribers) and not self._closed  # a viewer came while it was stopping
                if not again:
                    self._pumping = None
            if again:
                asyncio.ensure_future(self._run())

    async def _pump_while_wanted(self) -> None:
        backoff_s = self._backoff_min_s
        while self._wanted():
            stream: AsyncIterator[object] | None = None
            try:
                stream = self._open_stream()
                async for item in stream:
                    with self._lock:
                        self._latest_item = item
                        self._version += 1
                        self._lock.notify_all()
                    self._tell_listeners()
                    self._set_status(StreamStatus(True, "live"))
                    backoff_s = self._backoff_min_s
                    if not self._wanted():
                        break
            except asyncio.CancelledError:
                raise
            except Exception as error:  # noqa: BLE001 - any upstream failure means: reconnect later
                log.info("%s: upstream failed (%s)", self.name, error)
            finally:
                if stream is not None:
                    self._cancel(stream)
            if self._wanted():  # the stream ended while people watch: the robot went away
                self._set_status(StreamStatus(False, "The robot is not answering; reconnecting."))
                await asyncio.sleep(backoff_s)
                backoff_s = min(backoff_s * 2, self._backoff_max_s)
