"""Latest-wins fan-out of one upstream stream to any number of viewers.

One pump thread per stream pulls from the robot while anyone watches; each message is packed once
and handed to every viewer. A slow viewer skips to the newest message: it never slows the others
and never builds a backlog.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

log = logging.getLogger(__name__)

Packed = TypeVar("Packed")


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
    """Pumps open_stream() while subscribed, packing each item once with pack()."""

    def __init__(
        self,
        name: str,
        open_stream: Callable[[], Iterator[object]],
        pack: Callable[[Any], Packed],  # takes what open_stream yields
        cancel: Callable[[Iterator[object]], None],
        backoff_s: tuple[float, float] = (0.2, 5.0),
    ) -> None:
        self.name = name
        self._open_stream = open_stream
        self._pack = pack
        self._cancel = cancel
        self._backoff_min_s, self._backoff_max_s = backoff_s
        self._lock = threading.Condition()
        self._subscribers: set[Subscription[Packed]] = set()
        self._latest: Packed | None = None
        self._version = 0
        self._status = StreamStatus(True, "connecting")
        self._status_version = 0
        self._pump: threading.Thread | None = None
        self._stream: Iterator[object] | None = None
        self._closed = False
        self._listeners: list[Callable[[], None]] = []
        self.messages_packed = 0

    def listen(self, news: Callable[[], None]) -> None:
        """Calls news() (from the pump's thread; it must not block) after every new message or status change and
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
            if self._pump is None:
                self._pump = threading.Thread(target=self._run, name=f"fanout-{self.name}", daemon=True)
                self._pump.start()
        return subscription

    def unsubscribe(self, subscription: Subscription[Packed]) -> None:
        """Removes a viewer; the last one leaving cancels the upstream stream."""
        with self._lock:
            self._subscribers.discard(subscription)
            idle = not self._subscribers
            stream = self._stream
        if idle and stream is not None:
            self._cancel(stream)

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

    def wait_newer(self, seen_version: int, timeout_s: float) -> tuple[Packed | None, int]:
        """The latest message if newer than seen_version (waiting up to timeout_s), and its version."""
        deadline = time.monotonic() + timeout_s
        with self._lock:
            while self._version <= seen_version and not self._closed:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not self._lock.wait(remaining):
                    return None, seen_version
            if self._version <= seen_version:
                return None, seen_version
            return self._latest, self._version

    def status_with_version(self) -> tuple[StreamStatus, int]:
        """The upstream status and a number that changes whenever it does."""
        with self._lock:
            return self._status, self._status_version

    def close(self) -> None:
        """Stops the pump and wakes every viewer (application shutdown)."""
        with self._lock:
            self._closed = True
            stream = self._stream
            self._lock.notify_all()
        self._tell_listeners()
        if stream is not None:
            self._cancel(stream)

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

    def _continue_or_retire(self) -> bool:
        """True to keep pumping; otherwise the pump retires under the lock so subscribe() starts another."""
        with self._lock:
            if self._subscribers and not self._closed:
                return True
            self._pump = None
            return False

    def _run(self) -> None:
        backoff_s = self._backoff_min_s
        while self._continue_or_retire():
            try:
                stream = self._open_stream()
                with self._lock:
                    self._stream = stream
                for item in stream:
                    packed = self._pack(item)
                    with self._lock:
                        self._latest = packed
                        self._version += 1
                        self.messages_packed += 1
                        self._lock.notify_all()
                    self._tell_listeners()
                    self._set_status(StreamStatus(True, "live"))
                    backoff_s = self._backoff_min_s
                    if not self._wanted():
                        break
            except Exception as error:  # noqa: BLE001 - any upstream failure means: reconnect later
                log.info("%s: upstream failed (%s)", self.name, error)
            finally:
                with self._lock:
                    self._stream = None
            if self._wanted():  # the stream ended while people watch: the robot went away
                self._set_status(StreamStatus(False, "The robot is not answering; reconnecting."))
                time.sleep(backoff_s)
                backoff_s = min(backoff_s * 2, self._backoff_max_s)
