"""Who controls each robot and who waits: one control row per robot, one queue entry per user and robot."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import DateTime, ForeignKey, String, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class RobotControl(Base):
    """The single row per robot that says who controls it; every change to a robot's queue locks it first.

    One row per robot (the primary key) makes "at most one controller" a property of the schema;
    locking it serialises queue changes across worker processes.
    """

    __tablename__ = "robot_control"

    robot_name: Mapped[str] = mapped_column(String(32), primary_key=True)
    controller_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"))
    token: Mapped[str | None] = mapped_column(String(64))
    turn_started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    turn_ends_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))  # None: no limit
    faulted: Mapped[bool] = mapped_column(default=False)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class QueueEntry(Base):
    """A user connected to a robot: waiting, or the controller. The seat belongs to the user."""

    __tablename__ = "queue_entries"
    __table_args__ = (UniqueConstraint("robot_name", "user_id", name="uq_queue_entries_robot_user"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str] = mapped_column(String(32), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    enqueued_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    last_seen_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class PoolQueueEntry(Base):
    """A user waiting for any robot of a kind; bound to one when a robot of the kind can start their turn."""

    __tablename__ = "pool_queue_entries"
    __table_args__ = (UniqueConstraint("kind", "user_id", name="uq_pool_queue_entries_kind_user"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    kind: Mapped[str] = mapped_column(String(32), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    enqueued_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    last_seen_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
