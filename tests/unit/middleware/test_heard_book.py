"""The seats' "last heard" book: a batch that fails goes again with the next, and when its process leaves what is
pending is written and its thread ends."""

from __future__ import annotations

import threading
from contextlib import contextmanager
from datetime import UTC, datetime, timedelta

import pytest

from middleware.access.heard import HeardBook


class WrittenBatches:
    """A session factory that keeps each batch's rows instead of writing them."""

    def __init__(self, failures: int = 0) -> None:
        self.batches: list[list[dict]] = []
        self.failures = failures  # batches refused first, as by a database away for a while

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
                if outer.failures:
                    outer.failures -= 1
                    raise ConnectionError("the database is away")
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


def test_a_batch_the_database_refused_goes_again_with_the_next_and_a_newer_time_wins() -> None:
    sessions = WrittenBatches(failures=1)
    book = HeardBook(sessions, interval_s=60.0)
    first = datetime(2026, 11, 30, 9, 0, tzinfo=UTC)
    book.note("lab-1", 7, first)
    book.note("lab-2", 8, first)
    with pytest.raises(ConnectionError):
        book.write()
    book.note("lab-2", 8, first + timedelta(seconds=3))  # heard again while the database was away

    assert book.write() == 2
    assert sorted(sessions.batches[0], key=lambda row: row["seat_robot"]) == [
        {"seat_robot": "lab-1", "seat_user": 7, "heard_at": first},
        {"seat_robot": "lab-2", "seat_user": 8, "heard_at": first + timedelta(seconds=3)}]
    book.close()
