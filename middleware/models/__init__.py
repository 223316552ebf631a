"""Every SQLAlchemy model, imported here so Alembic's env.py sees the whole metadata."""

from __future__ import annotations

from middleware.models.accounts import Role, User
from middleware.models.base import Base

__all__ = ["Base", "Role", "User"]
