"""Usage analytics' own records (issue 30): what the other tables do not keep. Queue waits and robot outages are
written by the round-robin rule (access/round_robin.py), lessons watched and tours followed by teaching; sessions
come from the recordings index. The xAPI outbox holds each statement for the Learning Record Store until sent."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import CheckConstraint, DateTime, Float, ForeignKey, Index, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base

LEARNING_EVENT_KINDS = ("lesson_watched", "tour_followed")
OUTBOX_STATES = ("pending", "sent", "failed")


class QueueWait(Base):
    """One turn granted on a lab robot and how long its user waited for it (0 when the robot was free)."""

    __tablename__ = "analytics_queue_waits"
    __table_args__ = (CheckConstraint("wait_s >= 0", name="wait_not_negative"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str] = mapped_column(String(64))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    waited_from: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    granted_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), index=True)
    wait_s: Mapped[float] = mapped_column(Float)


class RobotOutage(Base):
    """A time a lab robot did not answer (the access rule paused its queue): from started_at to ended_at, open while
    it lasts."""

    __tablename__ = "analytics_robot_outages"
    __table_args__ = (Index("ix_analytics_robot_outages_robot_started", "robot_name", "started_at"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str] = mapped_column(String(64))
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    ended_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))


class LearningEvent(Base):
    """A lesson watched to its end or a tour followed to its last step, by one person."""

    __tablename__ = "analytics_learning_events"
    __table_args__ = (
        CheckConstraint("kind IN ('lesson_watched', 'tour_followed')", name="kind_known"),
        Index("ix_analytics_learning_events_user_kind", "user_id", "kind", "object_id"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    kind: Mapped[str] = mapped_column(String(16))
    object_id: Mapped[int] = mapped_column(Integer)
    at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now, index=True)


class XapiStatement(Base):
    """An xAPI statement waiting for (or sent to) the Learning Record Store: the outbox, retried until sent; the
    statement's id is unique, so a statement is queued once whichever worker builds it. A deleted account's
    statements go with it (never sent after)."""

    __tablename__ = "xapi_outbox"
    __table_args__ = (
        CheckConstraint("status IN ('pending', 'sent', 'failed')", name="status_known"),
        Index("ix_xapi_outbox_due", "status", "next_try_at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    statement_id: Mapped[str] = mapped_column(String(36), unique=True)
    # Whose learning record it is: deleting the account deletes its statements, sent or not.
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    statement_json: Mapped[str] = mapped_column(Text)
    status: Mapped[str] = mapped_column(String(16), default="pending")
    tries: Mapped[int] = mapped_column(default=0)
    next_try_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    claimed_by: Mapped[str | None] = mapped_column(String(96))
    claimed_until: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    last_error: Mapped[str | None] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    sent_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
