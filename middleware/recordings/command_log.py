"""The command observer the one command path calls (create_app hands it in): it only queues the note, so the
command's answer never waits for the recorder; a thread of this process writes the queued notes to the database,
where the recorder of the robot's session (in whichever process is elected) reads them."""

from __future__ import annotations

import json
import logging
import queue
import threading
from collections.abc import Callable

from flask import has_request_context, request
from sqlalchemy import insert
from sqlalchemy.orm import Session

from middleware.access.commands import CommandNote
from middleware.models.recordings import RecordedCommand

log = logging.getLogger(__name__)
WRITE_EVERY_S = 0.5  # the recorder copies the rows once a second, and waits for one more write at a session's end
QUEUE_LIMIT = 10_000  # notes waiting; past it a note is dropped (counted), never waited for

# The page or API a command came from, when its sender named no source (the drive pad's socket has no request).
_SOURCE_BY_BLUEPRINT = {"skills": "skill_panel", "plans": "plan", "lessons": "cue", "tours": "tour_step",
                        "classes": "tutor", "api": "api", "practice": "pad", "lab": "pad", "limits": "pad",
                        "experiment": "pad", "teleperception": "pad", "pools": "pad"}


def inferred_source(note: CommandNote) -> str:
    """The note's source: as its sender named it, else from the request that sent it, else the drive pad."""
    if note.source:
        return note.source
    if has_request_context():
        return _SOURCE_BY_BLUEPRINT.get(request.blueprint or "", "pad")
    return "pad"


class CommandSink:
    """Queues notes from any thread and writes them in batches from a thread of its own."""

    def __init__(self, sessions: Callable[[], Session]) -> None:
        self._sessions = sessions
        self._queue: queue.Queue[tuple[CommandNote, str]] = queue.Queue(QUEUE_LIMIT)
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self.dropped = 0

    def observe(self, note: CommandNote) -> None:
        """The observer, on the command's own path: queues the note with its source (which only the request can
        tell) and returns; the row is made by the writing thread (never blocks)."""
        try:
            self._queue.put_nowait((note, inferred_source(note)))
        except queue.Full:
            self.dropped += 1
            return
        if self._thread is None:
            self._start()

    def write_pending(self) -> int:
        """Writes every queued note now; how many."""
        rows: list[dict[str, object]] = []
        while True:
            try:
                rows.append(_row(*self._queue.get_nowait()))
            except queue.Empty:
                break
        if rows:
            with self._sessions() as session, session.begin():
                session.execute(insert(RecordedCommand), rows)
        return len(rows)

    def stop(self) -> None:
        """Writes what is queued and ends the thread."""
        self._stopped.set()
        thread = self._thread
        if thread is not None:
            thread.join(timeout=3)

    def _start(self) -> None:
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._write_forever, name="command-log", daemon=True)
                self._thread.start()

    def _write_forever(self) -> None:
        while not self._stopped.wait(WRITE_EVERY_S):
            self._write_once()
        self._write_once()

    def _write_once(self) -> None:
        try:
            self.write_pending()
        except Exception:  # noqa: BLE001 - the database away for a moment: the notes wait in the queue... or go
            log.exception("writing the command log failed")


def _row(note: CommandNote, source: str) -> dict[str, object]:
    return {"robot_name": note.robot_name[:64], "user_id": note.user_id, "sent_unix_s": note.sent_unix_s,
            "sequence": int(note.detail.get("sequence", 0) or 0),  # type: ignore[call-overload]
            "source": source[:24], "action": note.action[:24], "detail": json.dumps(note.detail, default=str)[:20_000],
            "accepted": note.accepted, "outcome": note.outcome[:200]}
