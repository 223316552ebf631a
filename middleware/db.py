"""Database engine, per-request sessions and migrations to head."""

from __future__ import annotations

from pathlib import Path

from alembic import command
from alembic.config import Config as AlembicConfig
from flask import Flask, g
from sqlalchemy import Engine, create_engine, event
from sqlalchemy.orm import Session, sessionmaker

MIGRATIONS_DIR = Path(__file__).resolve().parent.parent / "migrations"
_EXTENSION_KEY = "telelab.db"


def make_engine(url: str) -> Engine:
    """An engine for url; SQLite gets foreign keys on and a busy timeout for concurrent threads."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"timeout": 15, "check_same_thread": False})

        @event.listens_for(engine, "connect")
        def _sqlite_pragmas(dbapi_connection, _record) -> None:  # type: ignore[no-untyped-def]
            cursor = dbapi_connection.cursor()
            cursor.execute("PRAGMA foreign_keys=ON")
            cursor.execute("PRAGMA journal_mode=WAL")
            cursor.close()

        return engine
    return create_engine(url, pool_pre_ping=True)


def init_app(app: Flask) -> None:
    """Binds an engine and a session factory to app; sessions close at the end of each request."""
    engine = make_engine(app.config["DATABASE_URL"])
    app.extensions[_EXTENSION_KEY] = sessionmaker(bind=engine, expire_on_commit=False)

    @app.teardown_appcontext
    def _close_session(_exc: BaseException | None) -> None:
        session = g.pop("db_session", None)
        if session is not None:
            session.close()


def session_factory(app: Flask) -> sessionmaker[Session]:
    """The session factory bound to app (for CLI commands and background work)."""
    return app.extensions[_EXTENSION_KEY]


def get_session() -> Session:
    """The current request's session, created on first use."""
    if "db_session" not in g:
        from flask import current_app

        g.db_session = session_factory(current_app)()
    return g.db_session


def alembic_config(database_url: str) -> AlembicConfig:
    """An Alembic configuration pointing at migrations/ and database_url, with no ini file."""
    config = AlembicConfig()
    config.set_main_option("script_location", str(MIGRATIONS_DIR))
    config.set_main_option("path_separator", "os")
    config.attributes["database_url"] = database_url
    return config


def upgrade_to_head(database_url: str) -> None:
    """Migrates the database at database_url to the newest revision."""
    if database_url.startswith("sqlite:///") and not database_url.startswith("sqlite:///:memory:"):
        Path(database_url.removeprefix("sqlite:///")).parent.mkdir(parents=True, exist_ok=True)
    command.upgrade(alembic_config(database_url), "head")
