"""The login check of every request: while a worker hears ended logins announced (PostgreSQL), its verdict that a
login is open saves the read for HEARD_RECHECK_S (a console's request a second read the row every time with a verdict
of 1 s), yet a login ended in another worker is refused within the e2e bound (0.5 s), and a verdict never outlives the
login's idle end as read."""

from __future__ import annotations

import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import create_engine, event, update
from sqlalchemy.orm import Session

from tests.conftest import add_test_account, migrate_to_head

pytestmark = pytest.mark.postgres
REFUSED_WITHIN_S = 0.5  # tests/e2e/test_class_across_workers.py's bound across hosts


@pytest.fixture
def app_on_postgres(postgres_url: str) -> Iterator[object]:
    from middleware import create_app
    from middleware.db import session_factory
    from middleware.events import bus_of

    migrate_to_head(postgres_url)
    app = create_app({"DATABASE_URL": postgres_url, "SECRET_KEY": "k" * 32, "ROBOTS": (), "TESTING": True})
    engine = session_factory(app).kw["bind"]
    assert bus_of(engine).listening.wait(10), "the event listener never connected"
    try:
        yield app
    finally:
        engine.dispose()


def test_a_heard_verdict_saves_the_read_and_an_end_elsewhere_is_refused_at_once(app_on_postgres,
                                                                                  postgres_url: str) -> None:
    from middleware.auth import session_records
    from middleware.auth.session_records import ACCOUNTS_TOPIC, SessionLimits
    from middleware.db import session_factory
    from middleware.events import announce
    from middleware.models import LoginSession

    limits = SessionLimits(lifetime=timedelta(hours=8), idle=timedelta(minutes=30))
    engine = session_factory(app_on_postgres).kw["bind"]
    reads: list[str] = []
    event.listen(engine, "before_cursor_execute",
                 lambda _c, _cur, statement, *_: reads.append(statement) if "login_sessions" in statement else None)
    with session_factory(app_on_postgres)() as session:
        user_id = add_test_account(session, "verdict1", "student").id
        key = session_records.open_session(session, user_id, datetime.now(UTC))
        session.commit()
        assert session_records.is_open(session, key, user_id, limits, datetime.now(UTC))
        time.sleep(session_records.RECHECK_S + 0.2)
        reads.clear()
        assert session_records.is_open(session, key, user_id, limits, datetime.now(UTC))
        assert reads == [], "a verdict older than RECHECK_S read the row again while announcements were heard"

        # Another worker ends the login (an admin disabled the account there) and announces it.
        elsewhere = create_engine(postgres_url)
        try:
            with Session(elsewhere) as other:
                other.execute(update(LoginSession).where(LoginSession.user_id == user_id)
                              .values(ended_at=datetime.now(UTC)))
                announce(other, ACCOUNTS_TOPIC, str(user_id))
                other.commit()
                ended_at = time.monotonic()
        finally:
            elsewhere.dispose()
        while session_records.is_open(session, key, user_id, limits, datetime.now(UTC)):
            assert time.monotonic() - ended_at < REFUSED_WITHIN_S, "a login ended elsewhere was served on"
            time.sleep(0.01)


def test_a_verdict_never_outlives_the_logins_idle_end(app_on_postgres) -> None:
    from middleware.auth import session_records
    from middleware.auth.session_records import SessionLimits
    from middleware.db import session_factory

    limits = SessionLimits(lifetime=timedelta(hours=8), idle=timedelta(minutes=30))
    start = datetime.now(UTC)
    with session_factory(app_on_postgres)() as session:
        user_id = add_test_account(session, "verdict2", "student").id
        key = session_records.open_session(session, user_id, start)
        session.commit()
        assert session_records.is_open(session, key, user_id, limits, start + timedelta(minutes=29))
        assert not session_records.is_open(session, key, user_id, limits, start + timedelta(minutes=29, seconds=59)
                                           + limits.idle), "the verdict outlived the idle end"
