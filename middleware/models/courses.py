"""Courses, who is enrolled in them, invitations by link, and failed logins (for rate limiting)."""

from __future__ import annotations

from datetime import datetime

import sqlalchemy as sa
from sqlalchemy import CheckConstraint, DateTime, ForeignKey, Index, String, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base

DEFAULT_TURN_LENGTH_S = 120
DEFAULT_BOOKING_ALLOWANCE_MIN = 120
DEFAULT_GRADED_RUN_HOLD_MIN = 30


class Course(Base):
    """A course: its tutors set the turn length on shared robots, each student's booking allowance, and how long a
    graded run (an experimental test's attempt, a trial) may keep a shared robot."""

    __tablename__ = "courses"
    __table_args__ = (
        CheckConstraint("turn_length_s BETWEEN 10 AND 3600", name="turn_length_range"),
        CheckConstraint("booking_allowance_min BETWEEN 0 AND 10080", name="allowance_range"),
        CheckConstraint("graded_run_hold_min BETWEEN 5 AND 240", name="graded_run_hold_range"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    code: Mapped[str] = mapped_column(String(32), unique=True)
    title: Mapped[str] = mapped_column(String(200))
    turn_length_s: Mapped[int] = mapped_column(default=DEFAULT_TURN_LENGTH_S)
    booking_allowance_min: Mapped[int] = mapped_column(default=DEFAULT_BOOKING_ALLOWANCE_MIN)  # per week
    # The longest a graded attempt or an experiment trial keeps a shared robot past the turn length.
    graded_run_hold_min: Mapped[int] = mapped_column(default=DEFAULT_GRADED_RUN_HOLD_MIN,
                                                     server_default=str(DEFAULT_GRADED_RUN_HOLD_MIN))
    # The low-level settings its students may change on a robot they control (tutors and admins change all): the
    # velocity ceilings yes by default (slowing down is an exercise), the watchdog no (it is the lab's safety net).
    students_set_velocity: Mapped[bool] = mapped_column(default=True, server_default=sa.true())
    students_set_watchdog: Mapped[bool] = mapped_column(default=False, server_default=sa.false())
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class CourseMembership(Base):
    """A user enrolled in a course, as a student or as one of its tutors."""

    __tablename__ = "course_memberships"
    __table_args__ = (
        UniqueConstraint("course_id", "user_id", name="uq_course_memberships_course_user"),
        CheckConstraint("role IN ('student', 'tutor')", name="role_known"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    role: Mapped[str] = mapped_column(String(16))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Invitation(Base):
    """A single-use link that lets one person create an account (only the token's hash is stored)."""

    __tablename__ = "invitations"
    __table_args__ = (CheckConstraint("role IN ('student', 'tutor', 'admin')", name="role_known"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    role: Mapped[str] = mapped_column(String(16))
    course_id: Mapped[int | None] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"))
    created_by_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    expires_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    accepted_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    accepted_user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"))
    revoked_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))


class LoginFailure(Base):
    """One failed login, counted per account and per address over a sliding window."""

    __tablename__ = "login_failures"
    __table_args__ = (
        Index("ix_login_failures_username_at", "username", "at"),
        Index("ix_login_failures_address_at", "address", "at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    username: Mapped[str] = mapped_column(String(128))
    address: Mapped[str] = mapped_column(String(64))
    at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
