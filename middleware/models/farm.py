"""Simulated robots the farm runs for one user (practice robots): the only record of them every worker reads."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import DateTime, ForeignKey, String
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class PersonalRobotRecord(Base):
    """A user's own simulated robot: its name, owner, the owner's controller token and where it listens.

    The row is written before the robot starts (it claims the name across workers); address is "" until
    the robot serves. The token never changes while the robot lives: nobody else ever controls it.
    """

    __tablename__ = "personal_robots"

    name: Mapped[str] = mapped_column(String(32), primary_key=True)
    owner_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), unique=True)
    owner_name: Mapped[str] = mapped_column(String(64))
    scene: Mapped[str] = mapped_column(String(64))
    token: Mapped[str] = mapped_column(String(64))
    address: Mapped[str] = mapped_column(String(255), default="")
    backend: Mapped[str] = mapped_column(String(16))
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    last_used_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
