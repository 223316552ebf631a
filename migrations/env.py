"""Alembic environment: migrates the database named by the caller (see middleware.db.alembic_config)."""

from __future__ import annotations

import os

from alembic import context
from sqlalchemy import create_engine, pool

from middleware.models import Base

target_metadata = Base.metadata


def database_url() -> str:
    """The URL handed over by middleware.db, else TELELAB_DATABASE_URL (for the plain alembic CLI)."""
    url = context.config.attributes.get("database_url") or os.environ.get("TELELAB_DATABASE_URL")
    if not url:
        raise RuntimeError("No database URL: set TELELAB_DATABASE_URL or use `telelab db upgrade`.")
    return url


def run_migrations_offline() -> None:
    """Writes the SQL instead of running it."""
    context.configure(url=database_url(), target_metadata=target_metadata, render_as_batch=True,
                      literal_binds=True)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    """Runs the migrations on a live connection (batch mode so SQLite can alter tables)."""
    connectable = context.config.attributes.get("connection")
    if connectable is not None:
        context.configure(connection=connectable, target_metadata=target_metadata, render_as_batch=True)
        with context.begin_transaction():
            context.run_migrations()
        return
    engine = create_engine(database_url(), poolclass=pool.NullPool)
    with engine.connect() as connection:
        context.configure(connection=connection, target_metadata=target_metadata, render_as_batch=True)
        with context.begin_transaction():
            context.run_migrations()
    engine.dispose()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
