"""Changes other workers must see, announced through the database they share; the tables stay the truth.

`announce(session, topic, key)` is called in the transaction that makes the change, and the announcement is
delivered when (and only if) it commits: with PostgreSQL as `NOTIFY telelab_events, 'topic:key'` (a name or an
id, never more than a few hundred bytes), heard by every process of the cluster; with SQLite (one process, the
embedded default) in this process, queued by the session's after-commit hook. `listen(engine, topic, callback)`
calls callback(key) for each announcement of topic, in the bus's own thread (never in the announcer's, which may
hold locks the callback takes); the receiver reads what changed from the tables. When the PostgreSQL listener
loses its connection it reconnects and calls every callback with key None: "anything may have changed
meanwhile, read it all again". `KeptAnswers` is the receiving side most readers want: answers read from the tables,
kept by this process until an announcement of their topic drops them.
"""

from __future__ import annotations

import contextlib
import logging
import math
import queue
import threading
import time
from collections import defaultdict, deque
from collections.abc import Callable, Hashable
from itertools import islice
from typing import Generic, TypeVar

from sqlalchemy import Connection, Engine, event, text
from sqlalchemy.orm import Session

log = logging.getLogger(__name__)
CHANNEL = "telelab_events"
MAX_PAYLOAD = 200
RECENT_DROPS = 256  # the drops a kept answer's read is compared with (a read outlasting more keeps nothing)
RECONNECT_S = 1.0
RECONNECT_MAX_S = 30.0
DISPATCHER_IDLE_S = 5.0

Callback = Callable[[str | None], None]
K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


class EventBus:
    """One database's announcements in this process: the callbacks per topic, and (PostgreSQL) the listener."""

    def __init__(self, engine: Engine) -> None:
        self._engine = engine
        self._lock = threading.Lock()
        self._callbacks: dict[str, list[Callback]] = defaultdict(list)
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.listening = threading.Event()  # set while the PostgreSQL listener is connected
        self._queued: queue.SimpleQueue[tuple[str, str | None]] = queue.SimpleQueue()
        self._dispatcher: threading.Thread | None = None
        event.listen(engine, "engine_disposed", lambda _engine: self.close())

    @property
    def shared(self) -> bool:
        """Whether other processes hear this bus (PostgreSQL) or only this one (SQLite)."""
        return self._engine.dialect.name == "postgresql"

    def listen(self, topic: str, callback: Callback) -> Callable[[], None]:
        """Calls callback(key) for every committed announcement of topic; returns the function that stops it."""
        with self._lock:
            self._callbacks[topic].append(callback)
            if self.shared and self._thread is None:
                self._stop.clear()
                self._thread = threading.Thread(target=self._listen_forever, name="event-bus", daemon=True)
                self._thread.start()

        def stop() -> None:
            with self._lock, contextlib.suppress(ValueError):
                self._callbacks[topic].remove(callback)

        return stop

    def close(self) -> None:
        """Stops the listener thread (when its engine is disposed, too)."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(5)

    def post(self, topic: str, key: str | None) -> None:
        """Delivers an announcement of this process from the bus's dispatcher thread (started when needed)."""
        self._queued.put((topic, key))
        with self._lock:
            if self._dispatcher is None:
                self._dispatcher = threading.Thread(target=self._dispatch, name="event-dispatch", daemon=True)
                self._dispatcher.start()

    def _dispatch(self) -> None:
        while True:
            try:
                topic, key = self._queued.get(timeout=DISPATCHER_IDLE_S)
            except queue.Empty:
                with self._lock:
                    if self._queued.empty():
                        self._dispatcher = None
                        return
                continue
            self.deliver(topic, key)

    def deliver(self, topic: str, key: str | None) -> None:
        """Calls topic's callbacks (every topic's when topic is empty: a resynchronisation)."""
        with self._lock:
            callbacks = [c for t, cs in self._callbacks.items() if not topic or t == topic for c in cs]
        for callback in callbacks:
            try:
                callback(key)
            except Exception:  # noqa: BLE001 - one receiver's failure must not stop the others
                log.exception("an event receiver of %r failed", topic)

    def _listen_forever(self) -> None:
        import psycopg

        conninfo = self._engine.url.set(drivername="postgresql").render_as_string(hide_password=False)
        pause_s, heard_before = RECONNECT_S, False
        while not self._stop.is_set():
            try:
                with psycopg.connect(conninfo, autocommit=True, connect_timeout=5) as connection:
                    connection.execute(f"LISTEN {CHANNEL}")
                    self.listening.set()
                    if heard_before:
                        log.info("the event listener is back")
                        self.deliver("", None)  # reconnected: what was announced meanwhile is lost, read it all
                    heard_before, pause_s = True, RECONNECT_S
                    while not self._stop.is_set():
                        for notice in connection.notifies(timeout=1.0):
                            topic, _, key = notice.payload.partition(":")
                            self.deliver(topic, key)
            except psycopg.Error as error:
                lost = self.listening.is_set()
                self.listening.clear()
                if "does not exist" in str(error):
                    log.info("the event listener stops: its database is gone")
                    return
                if lost:
                    log.warning("the event listener lost the database (%s); reconnecting", error.__class__.__name__)
                self._stop.wait(pause_s)
                pause_s = min(RECONNECT_MAX_S, pause_s * 2)


_buses: dict[int, EventBus] = {}
_buses_lock = threading.Lock()


def bus_of(engine: Engine) -> EventBus:
    """The bus of engine's database in this process."""
    with _buses_lock:
        bus = _buses.get(id(engine))
        if bus is None:
            bus = _buses[id(engine)] = EventBus(engine)
        return bus


def listen(engine: Engine, topic: str, callback: Callback) -> Callable[[], None]:
    """bus_of(engine).listen(topic, callback)."""
    return bus_of(engine).listen(topic, callback)


def announce_in_flush(session: Session, connection: Connection, topic: str, key: str) -> None:
    """announce() from a mapper event (during a flush, on its connection), delivered when the session commits."""
    payload = f"{topic}:{key}"[:MAX_PAYLOAD]
    if connection.dialect.name == "postgresql":
        connection.execute(text("SELECT pg_notify(:channel, :payload)"), {"channel": CHANNEL, "payload": payload})
        return
    bus = bus_of(connection.engine)
    event.listen(session, "after_commit", lambda _session: bus.post(topic, key[:MAX_PAYLOAD]), once=True)


def announce(session: Session, topic: str, key: str) -> None:
    """Announces that key of topic changed, delivered when session's transaction commits (nothing on rollback)."""
    payload = f"{topic}:{key}"[:MAX_PAYLOAD]
    engine = session.get_bind().engine
    if engine.dialect.name == "postgresql":
        session.execute(text("SELECT pg_notify(:channel, :payload)"), {"channel": CHANNEL, "payload": payload})
        return
    bus = bus_of(engine)
    event.listen(session, "after_commit", lambda _session: bus.post(topic, key[:MAX_PAYLOAD]), once=True)


class KeptAnswers(Generic[K, V]):
    """Answers read from the tables, kept by this process until an announcement of their topic drops them.

    An answer is kept heard_s while the process hears the announcements (PostgreSQL's listener connected), else
    short_s (SQLite's bus reaches no other process; a listener may be reconnecting), and never longer than the reader
    says of it. An announcement drops its key (keyed: the topic is announced with these keys) or every answer; a
    listener that reconnected drops every answer. An answer read while its key (or every answer) was dropped is given
    but not kept, so a read that raced a change never outlives the change's announcement; a drop of another key does
    not stop it being kept (a class starting 50 robots announces 50 names while each is read).
    """

    def __init__(self, engine: Engine, topic: str, short_s: float, heard_s: float, keyed: bool = True) -> None:
        self._engine, self._topic, self._keyed = engine, topic, keyed
        self._short_s, self._heard_s = short_s, heard_s
        self._lock = threading.Lock()
        self._answers: dict[K, tuple[V, float]] = {}  # key -> (answer, kept until [monotonic s])
        self._drops = 0
        self._dropped: deque[K | None] = deque(maxlen=RECENT_DROPS)  # the latest drops' keys (None: every answer)
        self._bus: EventBus | None = None

    def known(self, key: K) -> tuple[bool, V | None]:
        """(True, the answer) while one is kept for key, else (False, None): memory only, never a read."""
        with self._lock:
            kept = self._answers.get(key)
        if kept is not None and kept[1] > time.monotonic():
            return True, kept[0]
        return False, None

    def get(self, key: K, read: Callable[[], V], longest_s: Callable[[V], float] = lambda _answer: math.inf) -> V:
        """The answer kept for key, else read()'s, then kept at most longest_s(answer) seconds (0: not kept)."""
        found, answer = self.known(key)
        if found:
            return answer  # type: ignore[return-value]  # kept answers are V
        bus = self._listen()
        with self._lock:
            drops = self._drops
        answer = read()
        lifetime_s = min(self._heard_s if bus.shared and bus.listening.is_set() else self._short_s,
                         longest_s(answer))
        with self._lock:
            if lifetime_s > 0 and not self._dropped_since(drops, key):
                self._answers[key] = (answer, time.monotonic() + lifetime_s)
        return answer

    def _dropped_since(self, drops: int, key: K) -> bool:
        """Whether key's answer was dropped after the first `drops` drops (the lock held): a read outlasting more
        drops than are remembered is taken to have raced its own."""
        since = self._drops - drops
        if since > len(self._dropped):
            return True
        return any(dropped is None or dropped == key for dropped in islice(reversed(self._dropped), since))

    def drop(self, key: K | None = None) -> None:
        """Forgets key's answer (every answer: None), and any read under way is not kept."""
        with self._lock:
            self._drops += 1
            self._dropped.append(key)
            if key is None:
                self._answers.clear()
            else:
                self._answers.pop(key, None)

    def _heard(self, key: str | None) -> None:
        self.drop(key if self._keyed else None)  # type: ignore[arg-type]  # keyed: the topic's keys are K

    def _listen(self) -> EventBus:
        """The bus, listened to from the first read on (a process that never asks starts no listener)."""
        with self._lock:  # subscribed before any read is kept (the bus calls _heard without its own lock held)
            if self._bus is None:
                self._bus = bus_of(self._engine)
                self._bus.listen(self._topic, self._heard)
            return self._bus
