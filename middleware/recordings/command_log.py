"""The command observer the one command path calls (create_app hands it in): it only keeps the note, so the
command's answer never waits for the recorder; the keeper's tick hands the notes to the worker's writer child once a
second (recorder.py), which writes them to the command log, where the recorder of the robot's session (in whichever
process records it) reads them. No thread of its own and no database work in the worker."""

from __future__ import annotations

import contextlib
import json
from collections import deque

from flask import has_request_context, request

from middleware.access.commands import CommandNote

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
    """Keeps notes from any thread until the keeper's next tick hands them to the writer child (no thread, no
    database work here)."""

    def __init__(self) -> None:
        self._notes: deque[tuple[CommandNote, str]] = deque()
        self._back: list[dict[str, object]] = []  # rows a failed tick handed back
        self.dropped = 0

    def observe(self, note: CommandNote) -> None:
        """The observer, on the command's own path: keeps the note with its source (which only the request can
        tell) and returns (never blocks)."""
        if len(self._notes) >= QUEUE_LIMIT:
            self.dropped += 1
            return
        self._notes.append((note, inferred_source(note)))

    def take(self) -> list[dict[str, object]]:
        """The notes kept since the last take, as command log rows."""
        rows, self._back = self._back, []
        with contextlib.suppress(IndexError):
            while True:
                rows.append(_row(*self._notes.popleft()))
        return rows

    def put_back(self, rows: list[dict[str, object]]) -> None:
        """Rows the writer could not take this tick: they go with the next one."""
        self._back = [*rows, *self._back][:QUEUE_LIMIT]


def _row(note: CommandNote, source: str) -> dict[str, object]:
    return {"robot_name": note.robot_name[:64], "user_id": note.user_id, "sent_unix_s": note.sent_unix_s,
            "sequence": int(note.detail.get("sequence", 0) or 0),  # type: ignore[call-overload]
            "source": source[:24], "action": note.action[:24], "detail": json.dumps(note.detail, default=str)[:20_000],
            "accepted": note.accepted, "outcome": note.outcome[:200]}
