"""A connection a thread still held when its engine was disposed (a worker shutting down) is closed as it comes
back, not left open in the pool the engine let go of until the garbage collector finds it (PostgreSQL keeps the
session meanwhile; psycopg warns)."""

from __future__ import annotations

import pytest
from sqlalchemy import text

from middleware.db import make_engine


@pytest.mark.parametrize("database_url", ["sqlite", "postgresql"], indirect=True)
def test_a_connection_returned_after_dispose_is_closed(database_url: str) -> None:
    engine = make_engine(database_url)
    held = engine.connect()
    held.execute(text("SELECT 1"))
    dbapi_connection = held.connection.dbapi_connection
    engine.dispose()
    held.close()
    closed = dbapi_connection.closed if hasattr(dbapi_connection, "pgconn") else _sqlite_closed(dbapi_connection)
    assert closed
    with engine.connect() as fresh:  # the engine itself still serves
        assert fresh.execute(text("SELECT 1")).scalar() == 1
    engine.dispose()


def _sqlite_closed(connection) -> bool:
    import sqlite3

    try:
        connection.execute("SELECT 1")
    except sqlite3.ProgrammingError:
        return True
    return False
