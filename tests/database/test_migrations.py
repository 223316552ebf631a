"""Migrations bring an empty SQLite or PostgreSQL database to head, and the models match them."""

from __future__ import annotations

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import inspect
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.auth.services import AccountExists, authenticate, create_user
from middleware.db import alembic_config, make_engine, upgrade_to_head
from middleware.models import Base, User


def test_migrations_upgrade_an_empty_database_to_head(database_url: str) -> None:
    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    head = ScriptDirectory.from_config(alembic_config(database_url)).get_current_head()
    with engine.connect() as connection:
        assert MigrationContext.configure(connection).get_current_revision() == head
        assert "users" in inspect(connection).get_table_names()
    engine.dispose()


def test_models_match_the_migrations(database_url: str) -> None:
    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    with engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)
    engine.dispose()
    assert differences == [], f"models and migrations differ; write a revision: {differences}"


def test_upgrading_twice_changes_nothing(database_url: str) -> None:
    upgrade_to_head(database_url)
    upgrade_to_head(database_url)


def test_accounts_are_stored_hashed_and_usernames_are_unique(database_url: str) -> None:
    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    with Session(engine) as session:
        user = create_user(session, "Ada", "student", "a-long-enough-secret")
        session.commit()
        assert user.username == "ada"
        assert "a-long-enough-secret" not in user.password_hash
        assert user.password_hash.startswith("scrypt:")
        assert authenticate(session, "ada", "a-long-enough-secret") is not None
        assert authenticate(session, "ada", "wrong-password-here") is None
        with pytest.raises(AccountExists):
            create_user(session, "ada", "tutor", "another-long-secret")
        # The database itself refuses a duplicate, whatever the Python layer does.
        session.add(User(username="ada", role="student", password_hash="x"))
        with pytest.raises(IntegrityError):
            session.commit()
        session.rollback()
        session.add(User(username="eve", role="superuser", password_hash="x"))
        with pytest.raises(IntegrityError):
            session.commit()
    engine.dispose()
