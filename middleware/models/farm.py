"""Simulated robots the farm runs for one user (practice robots), and class sessions that give one to every
student of a course: the only record of them, which every worker reads."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import CheckConstraint, DateTime, ForeignKey, Index, String, UniqueConstraint, text
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
    # Started for an open class session: not stopped as idle while the session lasts, stopped when it ends.
    class_session_id: Mapped[int | None] = mapped_column(ForeignKey("class_sessions.id", ondelete="SET NULL"))


class ClassSession(Base):
    """A class in the lab: a tutor started it for a course; every enrolled student gets a robot of their own."""

    __tablename__ = "class_sessions"
    __table_args__ = (
        # At most one open session per course, across workers.
        Index("uq_class_sessions_open_course", "course_id", unique=True,
              sqlite_where=text("ended_at IS NULL"), postgresql_where=text("ended_at IS NULL")),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"))
    started_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"))
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    ended_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    scene: Mapped[str] = mapped_column(String(64), default="lab")  # every student's robot runs this scene
    # The class booking that opened it (at the slot's start, and that ends it at the slot's end); None: by hand.
    booking_id: Mapped[int | None] = mapped_column(ForeignKey("bookings.id", ondelete="SET NULL"))


class ClassSeat(Base):
    """One student's place in a class session, and how their robot's start went."""

    __tablename__ = "class_seats"
    __table_args__ = (
        UniqueConstraint("session_id", "user_id", name="uq_class_seats_session_user"),
        CheckConstraint("state IN ('starting', 'ready', 'failed', 'stopped')", name="state_known"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("class_sessions.id", ondelete="CASCADE"), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    state: Mapped[str] = mapped_column(String(16), default="starting")
    message: Mapped[str] = mapped_column(String(300), default="")
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
