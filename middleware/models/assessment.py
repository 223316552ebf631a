"""Assessment: the question bank, exams (quizzes, timed theory and experimental tests), attempts, reviews, survey."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, CheckConstraint, DateTime, ForeignKey, Index, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class Question(Base):
    """One question of a course's bank; spec holds the choices and the key, by kind."""

    __tablename__ = "assessment_questions"
    __table_args__ = (
        CheckConstraint("kind IN ('single', 'multiple', 'numeric', 'text', 'rating')", name="kind_known"),
        CheckConstraint("points > 0 AND points <= 100", name="points_range"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), index=True)
    kind: Mapped[str] = mapped_column(String(16))
    prompt: Mapped[str] = mapped_column(Text)
    topics: Mapped[list[str]] = mapped_column(JSON, default=list)
    spec: Mapped[dict[str, Any]] = mapped_column(JSON)
    points: Mapped[float] = mapped_column(default=1.0)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Exam(Base):
    """A quiz (practice, any number of attempts), or a timed theoretical or experimental test."""

    __tablename__ = "assessment_exams"
    __table_args__ = (
        CheckConstraint("kind IN ('quiz', 'theory', 'experimental')", name="kind_known"),
        CheckConstraint("duration_s IS NULL OR duration_s BETWEEN 10 AND 86400", name="duration_range"),
        CheckConstraint("max_attempts IS NULL OR max_attempts >= 1", name="attempts_range"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), index=True)
    title: Mapped[str] = mapped_column(String(200))
    kind: Mapped[str] = mapped_column(String(16))
    opens_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    closes_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    duration_s: Mapped[int | None] = mapped_column()
    max_attempts: Mapped[int | None] = mapped_column()  # None: unlimited (quizzes)
    question_ids: Mapped[list[int]] = mapped_column(JSON, default=list)
    task: Mapped[dict[str, Any] | None] = mapped_column(JSON)  # experimental: kind, target, rubric
    robot_name: Mapped[str | None] = mapped_column(String(64))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Attempt(Base):
    """One student's attempt; open_key is set only while in progress, so the database allows one at a time."""

    __tablename__ = "assessment_attempts"
    __table_args__ = (
        UniqueConstraint("open_key", name="uq_assessment_attempts_open_key"),
        CheckConstraint("status IN ('in_progress', 'submitted')", name="status_known"),
        Index("ix_assessment_attempts_exam_user", "exam_id", "user_id"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    exam_id: Mapped[int] = mapped_column(ForeignKey("assessment_exams.id", ondelete="CASCADE"))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    status: Mapped[str] = mapped_column(String(16), default="in_progress")
    open_key: Mapped[str | None] = mapped_column(String(64))  # "<exam>:<user>" while in progress
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    deadline_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    submitted_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    submitted_by: Mapped[str | None] = mapped_column(String(16))  # student | deadline
    answers: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    # An experimental attempt's robot: the exam's, or the student's own one in a class session.
    robot_name: Mapped[str | None] = mapped_column(String(64))
    trace: Mapped[list[list[float]] | None] = mapped_column(JSON)  # [t_s, gx, gy, gth, ox, oy, oth]
    # Which process records the robot for an experimental attempt, and when it last stored the trace: another
    # worker takes the recording over when that goes stale (the process died).
    recorder_key: Mapped[str | None] = mapped_column(String(96))
    recorder_heard_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    results: Mapped[list[dict[str, Any]] | None] = mapped_column(JSON)  # graded items at submission
    auto_score: Mapped[float | None] = mapped_column()
    max_score: Mapped[float | None] = mapped_column()


class AttemptReview(Base):
    """A tutor's override of one item's mark (with a reason) or a comment; never edits the attempt itself."""

    __tablename__ = "assessment_reviews"

    id: Mapped[int] = mapped_column(primary_key=True)
    attempt_id: Mapped[int] = mapped_column(ForeignKey("assessment_attempts.id", ondelete="CASCADE"), index=True)
    author_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    item: Mapped[str | None] = mapped_column(String(32))  # question id or "task"; None for a comment on the whole
    points: Mapped[float | None] = mapped_column()  # the overriding mark, None for a comment only
    reason: Mapped[str] = mapped_column(Text, default="")
    comment: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class SurveyResponse(Base):
    """One student's answers to a course's system evaluation questionnaire (one per student and course)."""

    __tablename__ = "assessment_survey_responses"
    __table_args__ = (UniqueConstraint("course_id", "user_id", name="uq_assessment_survey_responses_course_user"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    ratings: Mapped[dict[str, int]] = mapped_column(JSON)
    comments: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class CourseSurvey(Base):
    """The survey a course's tutor wrote (statements rated 1-5, labelled ends); a course without one uses the
    2003 paper's seven statements. Fixed once a student has answered, so answers always match their statements."""

    __tablename__ = "course_surveys"

    id: Mapped[int] = mapped_column(primary_key=True)
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), unique=True)
    title: Mapped[str] = mapped_column(String(120))
    statements: Mapped[list[dict[str, str]]] = mapped_column(JSON)  # [{key, text, low_label, high_label}]
    author_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
