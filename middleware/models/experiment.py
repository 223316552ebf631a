"""The teleoperation-under-delay experiment: per-user injected video delay, and the trials run under it."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import Boolean, CheckConstraint, DateTime, Float, ForeignKey, Integer, String
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base

MAX_INJECTED_DELAY_S = 7.0
TRIAL_OPEN = "assigned"  # a trial's status until it is recorded or given up


class VideoDelay(Base):
    """A tutor's added delay on one user's camera and telemetry on every robot, applied by every worker's relay
    (commands are not delayed). A trial's delay is not stored here: it is the open trial's own, on its robot."""

    __tablename__ = "video_delays"
    __table_args__ = (CheckConstraint("delay_s >= 0 AND delay_s <= 7", name="delay_in_range"),)

    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), primary_key=True)
    delay_s: Mapped[float] = mapped_column(Float)
    set_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Trial(Base):
    """One run of a course by a student in an assigned condition (course, delay, feedback on/off); while it is open
    its delay is on the student's video of its robot, and of no other robot."""

    __tablename__ = "experiment_trials"
    __table_args__ = (
        CheckConstraint("course IN ('course-A', 'course-B')", name="course_known"),
        CheckConstraint("status IN ('assigned', 'completed', 'abandoned')", name="status_known"),
        CheckConstraint("delay_s >= 0 AND delay_s <= 7", name="trial_delay_in_range"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    # The class course the trial counts for (its tutors read it); None for a student of no course (admins read it).
    course_id: Mapped[int | None] = mapped_column(ForeignKey("courses.id", ondelete="SET NULL"), index=True,
                                                  nullable=True)
    robot_name: Mapped[str] = mapped_column(String(64))
    course: Mapped[str] = mapped_column(String(16))
    delay_s: Mapped[float] = mapped_column(Float)
    feedback: Mapped[bool] = mapped_column(Boolean)
    status: Mapped[str] = mapped_column(String(16), default="assigned")
    total_time_s: Mapped[float | None] = mapped_column(Float, nullable=True)
    errors: Mapped[int] = mapped_column(Integer, default=0)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
