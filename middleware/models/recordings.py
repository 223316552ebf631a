"""Recordings: the index of every controlled session recorded to MCAP (who, robot, kind, start, end, what ended it,
command/skill/plan counts: what usage analytics reads), and the commands every worker saw, waiting for the recorder."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import BigInteger, Boolean, CheckConstraint, DateTime, Float, ForeignKey, Index, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base

RECORDING_KINDS = ("turn", "practice", "plan_run", "exercise_run", "test_attempt", "experiment_trial",
                   "class_session")
RECORDING_STATES = ("recording", "ready", "failed")


class Recording(Base):
    """One controlled session: one person controlling one robot from started_at to ended_at; its MCAP parts live in
    the shared recordings directory under the id. A row with ended_at NULL is being recorded by the elected
    process (whichever it is now); status says whether its file is complete."""

    __tablename__ = "recordings"
    __table_args__ = (
        CheckConstraint("kind IN ('turn', 'practice', 'plan_run', 'exercise_run', 'test_attempt', "
                        "'experiment_trial', 'class_session')", name="kind_known"),
        CheckConstraint("status IN ('recording', 'ready', 'failed')", name="status_known"),
        Index("ix_recordings_robot_open", "robot_name", "ended_at"),
        Index("ix_recordings_started_at", "started_at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    robot_name: Mapped[str] = mapped_column(String(64))
    kind: Mapped[str] = mapped_column(String(24))
    # What the session belongs to: an attempt's, a trial's, a class session's, an exercise's or a plan's id.
    ref_id: Mapped[int | None] = mapped_column(Integer)
    # Started by a call of the recordings API (an exercise run) rather than seen in the control tables.
    explicit: Mapped[bool] = mapped_column(Boolean, default=False)
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    ended_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    end_reason: Mapped[str | None] = mapped_column(String(32))  # turn_ended, handed_over, robot_stopped, ...
    status: Mapped[str] = mapped_column(String(16), default="recording")
    command_count: Mapped[int] = mapped_column(Integer, default=0)
    skill_count: Mapped[int] = mapped_column(Integer, default=0)
    plan_count: Mapped[int] = mapped_column(Integer, default=0)
    size_bytes: Mapped[int] = mapped_column(BigInteger, default=0)
    # The plan or code that produced the run, when one did (exported beside the MCAP).
    source_text: Mapped[str | None] = mapped_column(Text)
    source_name: Mapped[str | None] = mapped_column(String(200))
    # Which process records it now, and when it last flushed: another one takes over when that goes stale.
    recorder_key: Mapped[str | None] = mapped_column(String(96))
    heard_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))


class RecordedCommand(Base):
    """A command as the one command path saw it, in whichever worker: the recorder of the robot's open recording
    copies it into the MCAP file (rows older than a day are removed)."""

    __tablename__ = "recorded_commands"
    __table_args__ = (Index("ix_recorded_commands_robot_id", "robot_name", "id"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str] = mapped_column(String(64))
    user_id: Mapped[int | None] = mapped_column(Integer)
    sent_unix_s: Mapped[float] = mapped_column(Float)
    sequence: Mapped[int] = mapped_column(BigInteger, default=0)
    source: Mapped[str] = mapped_column(String(24))
    action: Mapped[str] = mapped_column(String(24))
    detail: Mapped[str] = mapped_column(Text, default="{}")  # JSON: velocities, skill and parameters, plan name
    accepted: Mapped[bool] = mapped_column(Boolean, default=True)
    outcome: Mapped[str] = mapped_column(String(200), default="")  # the goal id, or the refusal's code
