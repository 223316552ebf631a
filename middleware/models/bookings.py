"""Bookings of robot time."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import CheckConstraint, DateTime, ForeignKey, Index, String
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class Booking(Base):
    """A slot of one robot booked by a student (personal) or a tutor (class session); times in UTC.

    A pool booking names a kind instead (pool_kind): robot_name stays empty until the slot starts and a robot of
    the kind is bound to it."""

    __tablename__ = "bookings"
    __table_args__ = (
        CheckConstraint("ends_at > starts_at", name="ends_after_start"),
        CheckConstraint("kind IN ('personal', 'class')", name="kind_known"),
        CheckConstraint("robot_name IS NOT NULL OR pool_kind IS NOT NULL", name="robot_or_pool"),
        Index("ix_bookings_robot_starts", "robot_name", "starts_at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str | None] = mapped_column(String(32))
    pool_kind: Mapped[str | None] = mapped_column(String(32), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    course_id: Mapped[int | None] = mapped_column(ForeignKey("courses.id", ondelete="SET NULL"))
    kind: Mapped[str] = mapped_column(String(16))
    starts_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    ends_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    cancelled_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    checked_in_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    released_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))  # no-show given back
