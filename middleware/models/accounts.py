"""Accounts: people who log in, with one role each."""

from __future__ import annotations

import enum
from datetime import UTC, datetime

from sqlalchemy import CheckConstraint, DateTime, String
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.base import Base


class Role(enum.StrEnum):
    """What an account may do: students learn, tutors teach, admins run the lab."""

    STUDENT = "student"
    TUTOR = "tutor"
    ADMIN = "admin"


def utc_now() -> datetime:
    """The current time, timezone-aware in UTC."""
    return datetime.now(UTC)


def as_utc(moment: datetime) -> datetime:
    """A stored time as an aware UTC datetime (SQLite hands back naive ones; every stored time is UTC)."""
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


class User(Base):
    """A person with a login; the password is stored only as a salted KDF hash."""

    __tablename__ = "users"
    __table_args__ = (
        CheckConstraint("role IN ('student', 'tutor', 'admin')", name="role_known"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    username: Mapped[str] = mapped_column(String(64), unique=True)
    role: Mapped[str] = mapped_column(String(16))
    password_hash: Mapped[str] = mapped_column(String(255))
    is_active: Mapped[bool] = mapped_column(default=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)

    # Flask-Login's user protocol, written out so the model has no Flask import.
    @property
    def is_authenticated(self) -> bool:
        """Every loaded account is an authenticated one (anonymous users are another class)."""
        return True

    @property
    def is_anonymous(self) -> bool:
        """Accounts are never anonymous."""
        return False

    def get_id(self) -> str:
        """The id Flask-Login keeps in the session."""
        return str(self.id)
