"""Delivers new and deleted chat messages to this process's sockets, whichever process wrote them.

A message posted or deleted is announced on the event bus (middleware/events.py: PostgreSQL NOTIFY to every
process, or this process's own with SQLite) with its room's name. One thread per process, woken by those
announcements, reads each announced room that has sockets open here (one query pair per room, however many
viewers) and puts events on each subscriber's queue. Nothing is polled on a timer. The thread stops when the
last subscriber leaves. A room's cursor is the newest id read: services.post_message takes the id under the room's
lock (locking.lock_chat_room), so ids are committed in their order and no message still in flight has a lower id.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from flask import Flask

from middleware import events
from middleware.chat import services
from middleware.db import session_factory

log = logging.getLogger(__name__)
TOPIC = "chat"
_EXTENSION_KEY = "telelab.chat_hub"


class Subscription:
    """One socket's events: ("message", dict) and ("deleted", id); those at or before after_id are skipped."""

    def __init__(self, hub: ChatHub, robot_name: str) -> None:
        self.hub, self.robot_name = hub, robot_name
        self.after_id = 0
        self._events: queue.SimpleQueue[tuple[str, object]] = queue.SimpleQueue()
        self.on_put: Callable[[], object] = lambda: None  # how the socket learns of an event (must not block)

    def put(self, kind: str, payload: object) -> None:
        """Queues an event (called by the hub's thread)."""
        self._events.put((kind, payload))
        self.on_put()

    def drain(self) -> list[tuple[str, object]]:
        """The events queued since the last call."""
        events: list[tuple[str, object]] = []
        while True:
            try:
                kind, payload = self._events.get_nowait()
            except queue.Empty:
                return events
            if kind == "message" and payload.id <= self.after_id:  # type: ignore[attr-defined]
                continue  # already sent with the history
            events.append((kind, payload))

    def close(self) -> None:
        """Stops delivery."""
        self.hub.unsubscribe(self)


@dataclass
class _Room:
    last_id: int
    window_start_id: int
    announced_deletions: set[int] = field(default_factory=set)
    subscribers: set[Subscription] = field(default_factory=set)


class ChatHub:
    """The rooms with sockets open in this process, and the one thread that polls them."""

    def __init__(self, app: Flask) -> None:
        self._sessions = session_factory(app)
        self._lock = threading.Lock()
        self._rooms: dict[str, _Room] = {}
        self._thread: threading.Thread | None = None
        self._changed: set[str | None] = set()  # rooms announced since the thread last looked (None: all)
        self._wake = threading.Event()
        events.listen(self._sessions.kw["bind"], TOPIC, self._announced)

    def _announced(self, robot_name: str | None) -> None:
        with self._lock:
            if robot_name is None or robot_name in self._rooms:
                self._changed.add(robot_name)
                self._wake.set()

    def subscribe(self, robot_name: str) -> Subscription:
        """A subscription to the room; subscribe before reading the history so nothing falls between."""
        subscription = Subscription(self, robot_name)
        with self._sessions() as session:
            newest = services.latest_id(session, robot_name)
        with self._lock:
            room = self._rooms.get(robot_name)
            if room is None:
                room = self._rooms[robot_name] = _Room(last_id=newest, window_start_id=newest + 1)
            room.window_start_id = min(room.window_start_id, max(1, newest - services.HISTORY_LENGTH))
            room.subscribers.add(subscription)
            self._changed.add(robot_name)  # one read now: a message announced before the room was here
            self._wake.set()
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="chat-hub", daemon=True)
                self._thread.start()
        return subscription

    def unsubscribe(self, subscription: Subscription) -> None:
        """Removes the subscription; an empty room is forgotten (the thread ends with the last)."""
        with self._lock:
            room = self._rooms.get(subscription.robot_name)
            if room is not None:
                room.subscribers.discard(subscription)
                if not room.subscribers:
                    del self._rooms[subscription.robot_name]
            if not self._rooms:
                self._wake.set()

    def _run(self) -> None:
        while True:
            self._wake.wait()
            with self._lock:
                self._wake.clear()
                if not self._rooms:
                    self._thread = None
                    return
                changed, self._changed = self._changed, set()
                rooms = {name: room for name, room in self._rooms.items() if None in changed or name in changed}
            for name, room in rooms.items():
                try:
                    self._poll(name, room)
                except Exception:  # a database hiccup must not end delivery for everyone
                    log.exception("chat delivery of %s failed", name)

    def _poll(self, robot_name: str, room: _Room) -> None:
        with self._sessions() as session:
            fresh = services.recent_messages(session, robot_name, after_id=room.last_id, limit=200)
            gone = [i for i in services.deleted_ids(session, robot_name, room.window_start_id)
                    if i not in room.announced_deletions]
        with self._lock:
            subscribers = list(room.subscribers)
        for view in fresh:
            room.last_id = max(room.last_id, view.id)
            for subscriber in subscribers:
                subscriber.put("message", view)  # each socket words the author for its viewer
        for message_id in gone:
            room.announced_deletions.add(message_id)
            for subscriber in subscribers:
                subscriber.put("deleted", message_id)


def chat_hub(app: Flask) -> ChatHub:
    """The app's hub, created on first use."""
    hub = app.extensions.get(_EXTENSION_KEY)
    if hub is None:
        hub = app.extensions.setdefault(_EXTENSION_KEY, ChatHub(app))
    return hub
