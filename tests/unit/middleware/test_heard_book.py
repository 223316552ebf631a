"""The seats' "last heard" book when its process leaves: what is pending is written, and its thread ends."""

from __future__ import annotations

import threading
from contextlib import contextmanager
from datetime import UTC, datetime

from middleware.access.heard import HeardBook


class WrittenBatches:
    """A session factory that keeps each batch's rows instead of writing them."""

    def __init__(self) -> None:
        self.batches: list[list[dict]] = []

    def __call__(self):
        outer = self

        class Session:
            def __enter__(self):
                return self

            def __exit__(self, *_exc):
                return False

            @contextmanager
            def begin(self):
                yield

            def connection(self):
                return self

            def execute(self, _statement, rows):
                outer.batches.append(rows)

        return Session()


def writers() -> list[threading.Thread]:
    return [thread for thread in threading.enumerate() if thread.name == "heard-book"]


def test_closing_the_book_writes_what_was_heard_since_the_last_batch_and_ends_its_writer() -> None:
    sessions = WrittenBatches()
    book = HeardBook(sessions, interval_s=60.0)  # no batch of its own during the test
    heard_at = datetime(2026, 11, 30, 9, 0, tzinfo=UTC)
    before = len(writers())
    book.note("lab-1", 7, heard_at)
    assert len(writers()) == before + 1

    book.close()

    assert sessions.batches == [[{"seat_robot": "lab-1", "seat_user": 7, "heard_at": heard_at}]]
    assert len(writers()) == before
    book.note("lab-1", 7, heard_at)  # a socket still closing: kept in memory, no writer started again
    assert len(writers()) == before
