"""Programming exercises (issue 32): the catalogue, each student's code versions, and the runs graded from the
robot's ground truth. JSON columns are text, written and read by middleware/exercises/ only."""

from __future__ import annotations

from datetime import datetime

import sqlalchemy as sa
from sqlalchemy import DateTime, Float, ForeignKey, Integer, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class Exercise(Base):
    """One exercise of the catalogue: what the student reads and starts from, where it runs, how it is graded."""

    __tablename__ = "exercises"

    id: Mapped[int] = mapped_column(primary_key=True)
    slug: Mapped[str] = mapped_column(String(64), unique=True)
    title: Mapped[str] = mapped_column(String(120))
    statement: Mapped[str] = mapped_column(Text)
    template: Mapped[str] = mapped_column(Text)
    scene: Mapped[str] = mapped_column(String(64), default="lab")
    # The rubric's kind (bump_and_go, wall_following, reach_goal, cover_room, report_pose) and its parameters.
    rubric_json: Mapped[str] = mapped_column(Text)
    # The practice start [x_m, y_m, theta_rad] and the region hidden submission starts are drawn from.
    start_json: Mapped[str] = mapped_column(Text)
    random_starts_json: Mapped[str] = mapped_column(Text, default="null")
    time_limit_s: Mapped[float] = mapped_column(Float, default=60.0)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class ExerciseCode(Base):
    """One version of a student's code for an exercise (every run saves one; none is rewritten)."""

    __tablename__ = "exercise_codes"

    id: Mapped[int] = mapped_column(primary_key=True)
    exercise_id: Mapped[int] = mapped_column(ForeignKey("exercises.id", ondelete="CASCADE"), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    code: Mapped[str] = mapped_column(Text)
    saved_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class ExerciseRun(Base):
    """A run of a code version on a robot: a practice run, or a submission graded from the robot's pose log."""

    __tablename__ = "exercise_runs"

    id: Mapped[int] = mapped_column(primary_key=True)
    exercise_id: Mapped[int] = mapped_column(ForeignKey("exercises.id", ondelete="CASCADE"), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    code_id: Mapped[int] = mapped_column(ForeignKey("exercise_codes.id", ondelete="CASCADE"))
    robot_name: Mapped[str] = mapped_column(String(64))
    mode: Mapped[str] = mapped_column(String(16))  # practice | submission
    seed: Mapped[int] = mapped_column(Integer, default=0)
    start_json: Mapped[str] = mapped_column(Text)  # [x_m, y_m, theta_rad] where the server placed the robot
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    ended_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    status: Mapped[str] = mapped_column(String(16), default="running")  # running | graded | failed
    fraction: Mapped[float | None] = mapped_column(Float, nullable=True)
    feedback: Mapped[str] = mapped_column(Text, default="")
    measurements_json: Mapped[str] = mapped_column(Text, default="{}")
    trace_json: Mapped[str] = mapped_column(Text, default="[]")  # [t_s, gx, gy, gth, ox, oy, oth] from the robot
    report_json: Mapped[str] = mapped_column(Text, default="null")  # what the code reported (localization only)


class ExerciseAssignment(Base):
    """An exercise attached to a course as a test: its grade is the best submission begun before the deadline."""

    __tablename__ = "exercise_assignments"
    __table_args__ = (UniqueConstraint("course_id", "exercise_id", name="uq_exercise_assignments_course_exercise"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), index=True)
    exercise_id: Mapped[int] = mapped_column(ForeignKey("exercises.id", ondelete="CASCADE"))
    deadline_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    points: Mapped[float] = mapped_column(Float, default=10.0)
    # Whether the course's students see its leaderboard (a ranking by mark); its tutors always do.
    leaderboard_open: Mapped[bool] = mapped_column(default=False, server_default=sa.false())
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
