"""SQLite's single-writer guard: a thread whose session holds the write lock and writes through a second session
is told so at once (it would wait for itself the whole busy timeout, stalling every writer), while other threads
still wait their turn as before."""

from __future__ import annotations

import threading
import time

import pytest
from sqlalchemy import update
from sqlalchemy.orm import Session

from middleware.db import WriteLockHeld, make_engine
from middleware.models import User
from tests.conftest import migrate_to_head


@pytest.fixture
def sqlite_engine(tmp_path):
    url = f"sqlite:///{tmp_path / 'guard.sqlite3'}"
    migrate_to_head(url)
    engine = make_engine(url)
    with Session(engine) as session:
        session.add_all([User(username="ann", role="student", password_hash="x"),
                         User(username="bob", role="student", password_hash="x")])
        session.commit()
    yield engine
    engine.dispose()


def _rename(session: Session, old: str, new: str) -> None:
    session.execute(update(User).where(User.username == old).values(username=new))


def test_a_second_connection_writing_while_the_first_holds_the_lock_is_refused_at_once(sqlite_engine) -> None:
    with Session(sqlite_engine) as request, Session(sqlite_engine) as second:
        _rename(request, "ann", "ann2")
        started = time.monotonic()
        with pytest.raises(WriteLockHeld):
            _rename(second, "bob", "bob2")
        assert time.monotonic() - started < 5, "refused, not after the 15 s busy timeout"
        request.commit()
        _rename(second, "bob", "bob2")  # the first one committed: the lock is free again
        second.commit()


def test_other_threads_wait_for_the_writer_and_then_write(sqlite_engine) -> None:
    written: list[str] = []

    def other_thread() -> None:
        with Session(sqlite_engine) as session:
            _rename(session, "bob", "bob3")
            session.commit()
            written.append("bob3")

    with Session(sqlite_engine) as first:
        _rename(first, "ann", "ann3")
        thread = threading.Thread(target=other_thread)
        thread.start()
        time.sleep(0.3)
        assert written == [], "it waits for the lock"
        first.commit()
    thread.join(10)
    assert written == ["bob3"]


def test_a_connection_given_back_to_the_pool_is_no_longer_this_threads_writer(sqlite_engine) -> None:
    with Session(sqlite_engine) as session:
        _rename(session, "ann", "ann4")
        session.commit()
    held_elsewhere = threading.Event()
    release = threading.Event()

    def another_writer() -> None:  # may take the pooled connection this thread wrote through
        with Session(sqlite_engine) as session:
            _rename(session, "ann4", "ann5")
            held_elsewhere.set()
            release.wait(10)
            session.commit()

    thread = threading.Thread(target=another_writer)
    thread.start()
    held_elsewhere.wait(10)
    writer = threading.Thread(target=release.set)
    writer.start()
    with Session(sqlite_engine) as session:
        _rename(session, "bob", "bob5")  # waits for the other thread's commit, never refused as our own lock
        session.commit()
    thread.join(10)
