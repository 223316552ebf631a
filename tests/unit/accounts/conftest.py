"""A migrated database (SQLite and PostgreSQL) with two courses, their tutors, students and an admin."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from sqlalchemy.orm import Session, sessionmaker

from middleware.db import make_engine
from tests.conftest import migrate_to_head
from tests.unit.bookings.conftest import People, seed


@pytest.fixture
def factory(database_url: str) -> Iterator[sessionmaker[Session]]:
    """Sessions on a migrated database."""
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    yield sessionmaker(bind=engine, expire_on_commit=False)
    engine.dispose()


@pytest.fixture
def people(factory: sessionmaker[Session]) -> People:
    """stud and stud2 in ROB1 (tut), tut2 tutoring ROB2, adm."""
    with factory() as session:
        return seed(session)
