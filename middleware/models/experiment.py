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
    # The trial's delay held the student's commands too (the course's protocol said so when it began).
    commands_delayed: Mapped[bool] = mapped_column(Boolean, default=False)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)


class ExperimentProtocol(Base):
    """What a course's tutor sets for the experiment (the thesis' protocol): the learning period before a student's
    first trial, whether a trial's delay holds the student's commands too (the distant proxy), and whether the
    participants' details go into the exports. A course without a row has the defaults."""

    __tablename__ = "experiment_protocols"
    __table_args__ = (CheckConstraint("learning_s >= 0 AND learning_s <= 3600", name="learning_in_range"),)

    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), primary_key=True)
    learning_s: Mapped[int] = mapped_column(Integer, default=300)
    delay_commands: Mapped[bool] = mapped_column(Boolean, default=False)
    export_participants: Mapped[bool] = mapped_column(Boolean, default=False)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Participant(Base):
    """A student's part in the experiment, asked once: their details (kept only with their consent), their learning
    period, and the counterbalanced order of conditions they run (a row of the course's Williams design)."""

    __tablename__ = "experiment_participants"
    __table_args__ = (
        CheckConstraint("age IS NULL OR (age >= 10 AND age <= 120)", name="age_in_range"),
        CheckConstraint("location IS NULL OR location IN ('lab', 'remote')", name="location_known"),
        CheckConstraint("games_experience IS NULL OR games_experience IN ('none', 'some', 'much')",
                        name="games_experience_known"),
        CheckConstraint("robots_experience IS NULL OR robots_experience IN ('none', 'some', 'much')",
                        name="robots_experience_known"),
    )

    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), primary_key=True)
    consent: Mapped[bool] = mapped_column(Boolean, default=False)
    age: Mapped[int | None] = mapped_column(Integer, nullable=True)
    location: Mapped[str | None] = mapped_column(String(8), nullable=True)
    games_experience: Mapped[str | None] = mapped_column(String(8), nullable=True)
    robots_experience: Mapped[str | None] = mapped_column(String(8), nullable=True)
    answered_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    learning_started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    # The course whose design gave the order (None: a student of no course) and the row of it, fixed at the first trial.
    order_course_id: Mapped[int | None] = mapped_column(ForeignKey("courses.id", ondelete="SET NULL"), nullable=True)
    order_index: Mapped[int | None] = mapped_column(Integer, nullable=True)
