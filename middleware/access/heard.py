"""When this process last heard each seat's clients, written to the queue table in one transaction per interval.

A console's sockets tell their seat they are alive every few seconds; a class of them, one write each, kept the
database busy with little else (500 single-row updates a second for 1 000 consoles). The book keeps the newest
time per seat and writes them all at once, each as heard, so a seat's grace still counts from its client's last
word; what the ticker reads may be one interval older, which the grace (15 s) absorbs.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from datetime import datetime
from typing import cast

from sqlalchemy import Table, bindparam, update
from sqlalchemy.orm import Session

from middleware.models import QueueEntry

log = logging.getLogger(__name__)
IDLE_WRITES = 15  # intervals with nothing to write before the writer's thread ends

_QUEUE = cast(Table, QueueEntry.__table__)
_BY_SEAT = (update(_QUEUE)
            .where(_QUEUE.c.robot_name == bindparam("seat_robot"), _QUEUE.c.user_id == bindparam("seat_user"))
            .values(last_seen_at=bindparam("heard_at")))


class HeardBook:
    """The newest "last heard" per (robot, user) since the last write; written every interval_s by a thread."""

    def __init__(self, sessions: Callable[[], Session], interval_s: float) -> None:
        self._sessions, self._interval_s = sessions, interval_s
        self._heard: dict[tuple[str, int], datetime] = {}
        self._lock = threading.Lock()
        self._writer: threading.Thread | None = None
        self._closed = threading.Event()

    def note(self, robot_name: str, user_id: int, heard_at: datetime) -> None:
        """The user's client on robot_name was heard at heard_at (memory only; written with the next batch)."""
        key = (robot_name, user_id)
        with self._lock:
            known = self._heard.get(key)
            if known is None or heard_at > known:
                self._heard[key] = heard_at
            if self._writer is None and not self._closed.is_set():
                self._writer = threading.Thread(target=self._write_forever, name="heard-book", daemon=True)
                self._writer.start()

    def write(self) -> int:
        """Writes what was heard since the last write; how many seats. A failed batch is kept for the next one."""
        with self._lock:
            heard, self._heard = self._heard, {}
        if heard:
            try:
                with self._sessions() as session, session.begin():
                    session.connection().execute(_BY_SEAT, [{"seat_robot": robot, "seat_user": user, "heard_at": at}
                                                            for (robot, user), at in heard.items()])
            except Exception:
                with self._lock:  # a seat heard again meanwhile keeps its newer time
                    self._heard = {**heard, **self._heard}
                raise
        return len(heard)

    def close(self) -> None:
        """Ends the writer after writing what is pending (a process leaving); later notes stay in memory."""
        self._closed.set()
        with self._lock:
            writer = self._writer
        if writer is not None and writer is not threading.current_thread():
            writer.join(5)
        try:
            self.write()
        except Exception:  # noqa: BLE001 - the process is leaving; the seat's grace absorbs one lost batch
            log.exception("writing when seats were last heard failed")

    def _write_forever(self) -> None:
        idle = 0
        while not self._closed.wait(self._interval_s):
            try:
                idle = 0 if self.write() else idle + 1
            except Exception:  # noqa: BLE001 - a failed batch goes again with the next one
                log.exception("writing when seats were last heard failed")
            with self._lock:
                if idle >= IDLE_WRITES and not self._heard:  # nobody connected for a while: the next note restarts it
                    self._writer = None
                    return
        with self._lock:
            self._writer = None
