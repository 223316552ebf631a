"""Database engine, the request's unit of work, sessions for work outside requests, and migrations to head.

The unit of work (indico's RH.process is the model): a request's session (get_session()) commits once,
after the view returned (a page, JSON, a redirect: all successes), and is rolled back when the view raised.
Services only flush; routes never commit or roll back. The error handlers (middleware/errors.py) call
discard_changes(); after_commit(callback) runs something outside the database (start a recorder, wake
sockets, re-read the robots table elsewhere) only once the change is committed. A WebSocket message or a
background thread uses unit_of_work(app): its own session, committed when the block ends, rolled back
when it raises.
"""

from __future__ import annotations

import sqlite3
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flask import Flask, Response, current_app, g
from sqlalchemy import Engine, create_engine, event
from sqlalchemy.orm import Session, sessionmaker

if TYPE_CHECKING:
    from alembic.config import Config as AlembicConfig

MIGRATIONS_DIR = Path(__file__).resolve().parent.parent / "migrations"
_EXTENSION_KEY = "telelab.db"


SQLITE_BUSY_TIMEOUT_S = 15
_WRITES = ("INSERT", "UPDATE", "DELETE", "REPLACE")


class WriteLockHeld(RuntimeError):
    """This thread already holds SQLite's write lock on another connection: the write it tried would wait for
    itself for the whole busy timeout and then fail with "database is locked"."""


def make_engine(url: str, pool_size: int = 5, max_overflow: int = 10) -> Engine:
    """An engine for url; SQLite gets foreign keys on, a busy timeout for concurrent threads, and the single-writer
    guard (one unit of work per thread); PostgreSQL a pool of pool_size + max_overflow (config.ConnectionBudget)."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"timeout": SQLITE_BUSY_TIMEOUT_S, "check_same_thread": False})

        @event.listens_for(engine, "connect")
        def _sqlite_pragmas(dbapi_connection, _record) -> None:
            cursor = dbapi_connection.cursor()
            cursor.execute("PRAGMA foreign_keys=ON")
            cursor.execute("PRAGMA journal_mode=WAL")
            cursor.close()

        event.listen(engine, "before_cursor_execute", _one_writer_per_thread)
    else:
        engine = create_engine(url, pool_pre_ping=True, pool_size=pool_size, max_overflow=max_overflow)
    _close_what_returns_after_dispose(engine)
    return engine


def _close_what_returns_after_dispose(engine: Engine) -> None:
    """A connection a thread still held when the engine was disposed (shutting down) goes back to the pool the
    engine let go of, where nothing closes it: the server would keep the session until the garbage collector. It is
    closed as it comes back."""

    @event.listens_for(engine, "checkout")
    def _note_the_pool(_dbapi_connection, record, _proxy) -> None:
        record.info["telelab.pool"] = id(engine.pool)

    @event.listens_for(engine, "checkin")
    def _close_if_orphaned(dbapi_connection, record) -> None:
        if dbapi_connection is not None and record.info.get("telelab.pool", id(engine.pool)) != id(engine.pool):
            record.invalidate()


_writing = threading.local()


def _one_writer_per_thread(connection, _cursor, statement: str, _parameters, _context, _executemany) -> None:
    """Refuses at once a write from a thread whose other connection holds SQLite's write lock.

    SQLite has one writer at a time; a thread that writes through a second session while its first one (the
    request's) holds the lock waits for itself for the busy timeout, stalling every other writer of the database
    meanwhile, and then fails. Such a place must write in the first session (one unit of work) or after its
    commit; this names it in the traceback instead of a 15 s stall.
    """
    if not statement.lstrip()[:7].upper().startswith(_WRITES):
        return
    mine = connection.connection  # this checkout of a pooled connection (it lets go of it when checked in)
    holders: dict[str, Any] = _writing.__dict__.setdefault("holders", {})
    database = str(connection.engine.url)  # a thread may write to two databases (tests make many apps)
    holder = holders.get(database)
    if holder is not None and holder is not mine:
        try:
            held = holder.dbapi_connection is not None and holder.dbapi_connection.in_transaction
        except sqlite3.ProgrammingError:  # closed
            held = False
        if held:
            raise WriteLockHeld("This thread writes through a second database connection while its first one holds "
                                "SQLite's write lock: write in the first session (one unit of work) or after it "
                                "commits.")
    holders[database] = mine


def init_app(app: Flask) -> None:
    """Binds an engine and a session factory to app, and the unit of work to its requests."""
    engine = make_engine(app.config["DATABASE_URL"], app.config.get("DB_POOL_SIZE", 5),
                         app.config.get("DB_MAX_OVERFLOW", 10))
    app.extensions[_EXTENSION_KEY] = sessionmaker(bind=engine, expire_on_commit=False)

    @app.after_request
    def _end_unit_of_work(response: Response) -> Response:
        # Runs for the view's response and for an error handler's (which discarded the changes first).
        # A failing commit raises: the request becomes a 500 and its handler rolls back.
        finish_request()
        return response

    @app.teardown_appcontext
    def _close_session(_exc: BaseException | None) -> None:
        g.pop("db_after_commit", None)
        session = g.pop("db_session", None)
        if session is not None:
            session.close()  # rolls back whatever was not committed (an error past every handler)


def finish_request() -> None:
    """Ends the request's unit of work: commit, then the after_commit callbacks; or, once discarded, roll back."""
    session: Session | None = g.get("db_session")
    callbacks: list[Callable[[], None]] = g.pop("db_after_commit", [])
    if g.get("db_discarded"):
        if session is not None:
            session.rollback()
        return
    if session is not None and session.in_transaction():
        session.commit()
    for callback in callbacks:
        callback()


def discard_changes() -> None:
    """Ends the request's unit of work without its changes: rolled back now (so the error page, or the form
    shown again, reads a clean session) and nothing is committed at the end. For the error handlers."""
    g.db_discarded = True
    g.pop("db_after_commit", None)
    session: Session | None = g.get("db_session")
    if session is not None:
        session.rollback()


def after_commit(callback: Callable[[], None]) -> None:
    """Runs callback once the request's changes are committed (never if they are discarded)."""
    g.setdefault("db_after_commit", []).append(callback)


@contextmanager
def unit_of_work(app: Flask) -> Iterator[Session]:
    """A session of its own, outside the request's (a socket's message, a background thread): committed when
    the block ends, rolled back when it raises."""
    with session_factory(app)() as session, session.begin():
        yield session


def session_factory(app: Flask) -> sessionmaker[Session]:
    """The session factory bound to app (for CLI commands and background work)."""
    return app.extensions[_EXTENSION_KEY]


def get_session() -> Session:
    """The current request's session, created on first use."""
    if "db_session" not in g:
        g.db_session = session_factory(current_app)()
    return g.db_session


def alembic_config(database_url: str) -> AlembicConfig:
    """An Alembic configuration pointing at migrations/ and database_url, with no ini file."""
    from alembic.config import Config as AlembicConfig  # alembic costs every process 0.3 s: only migrating needs it

    config = AlembicConfig()
    config.set_main_option("script_location", str(MIGRATIONS_DIR))
    config.set_main_option("path_separator", "os")
    config.attributes["database_url"] = database_url
    return config


def upgrade_to_head(database_url: str) -> None:
    """Migrates the database at database_url to the newest revision."""
    if database_url.startswith("sqlite:///") and not database_url.startswith("sqlite:///:memory:"):
        Path(database_url.removeprefix("sqlite:///")).parent.mkdir(parents=True, exist_ok=True)
    from alembic import command  # as in alembic_config

    command.upgrade(alembic_config(database_url), "head")
