"""LTI 1.3: the tool's own keys, registered platforms and deployments, people and courses matched from launches,
placed links, the launch store (nonces, states, launches) and the grade outbox."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, CheckConstraint, DateTime, ForeignKey, Index, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class LtiToolKey(Base):
    """One of the tool's RSA key pairs: the newest unretired one signs; every unretired one is in the JWKS."""

    __tablename__ = "lti_tool_keys"

    id: Mapped[int] = mapped_column(primary_key=True)
    kid: Mapped[str] = mapped_column(String(64), unique=True)
    private_pem: Mapped[str] = mapped_column(Text)
    public_pem: Mapped[str] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    retired_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))


class LtiPlatform(Base):
    """An LMS registered by an admin: its issuer and the client id it gave this tool, and its endpoints."""

    __tablename__ = "lti_platforms"
    __table_args__ = (UniqueConstraint("issuer", "client_id", name="uq_lti_platforms_issuer_client"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    issuer: Mapped[str] = mapped_column(String(255))
    client_id: Mapped[str] = mapped_column(String(255))
    auth_login_url: Mapped[str] = mapped_column(String(1000))
    auth_token_url: Mapped[str] = mapped_column(String(1000))
    key_set_url: Mapped[str] = mapped_column(String(1000))
    # The origins whose pages may frame Telelab's (frame-ancestors): the issuer's by default, and the LMS's own
    # site where it differs (Canvas's issuer is canvas.instructure.com, its pages the university's).
    frame_origins: Mapped[list[str]] = mapped_column(JSON, default=list)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class LtiDeployment(Base):
    """A deployment id of a platform: launches naming any other are refused."""

    __tablename__ = "lti_deployments"
    __table_args__ = (UniqueConstraint("platform_id", "deployment_id", name="uq_lti_deployments_platform_dep"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    platform_id: Mapped[int] = mapped_column(ForeignKey("lti_platforms.id", ondelete="CASCADE"))
    deployment_id: Mapped[str] = mapped_column(String(255))


class LtiIdentity(Base):
    """A Telelab account matched to a platform's person by issuer and subject, never by name or e-mail."""

    __tablename__ = "lti_identities"
    __table_args__ = (UniqueConstraint("issuer", "subject", name="uq_lti_identities_issuer_subject"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    issuer: Mapped[str] = mapped_column(String(255))
    subject: Mapped[str] = mapped_column(String(255))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), unique=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class LtiContext(Base):
    """An LMS course (issuer + context id) mapped to a Telelab course, with the service URLs its launches gave."""

    __tablename__ = "lti_contexts"
    __table_args__ = (UniqueConstraint("issuer", "context_id", name="uq_lti_contexts_issuer_context"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    platform_id: Mapped[int] = mapped_column(ForeignKey("lti_platforms.id", ondelete="CASCADE"))
    issuer: Mapped[str] = mapped_column(String(255))
    context_id: Mapped[str] = mapped_column(String(255))
    course_id: Mapped[int] = mapped_column(ForeignKey("courses.id", ondelete="CASCADE"), unique=True)
    memberships_url: Mapped[str | None] = mapped_column(String(1000))
    lineitems_url: Mapped[str | None] = mapped_column(String(1000))
    ags_scopes: Mapped[list[str]] = mapped_column(JSON, default=list)
    roster_synced_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))


class LtiLineItem(Base):
    """Where the grades of a test, or of an exercise attached to a course as a test, go in an LMS course's
    gradebook (the line item a launch of the placed link named): exactly one of exam_id, exercise_assignment_id."""

    __tablename__ = "lti_line_items"
    __table_args__ = (
        UniqueConstraint("context_id", "exam_id", name="uq_lti_line_items_context_exam"),
        UniqueConstraint("context_id", "exercise_assignment_id", name="uq_lti_line_items_context_exercise"),
        CheckConstraint("(exam_id IS NULL) <> (exercise_assignment_id IS NULL)", name="one_graded_item"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    context_id: Mapped[int] = mapped_column(ForeignKey("lti_contexts.id", ondelete="CASCADE"))
    exam_id: Mapped[int | None] = mapped_column(ForeignKey("assessment_exams.id", ondelete="CASCADE"), index=True)
    exercise_assignment_id: Mapped[int | None] = mapped_column(
        ForeignKey("exercise_assignments.id", ondelete="CASCADE"), index=True)
    lineitem_url: Mapped[str] = mapped_column(String(1000))


class LtiLaunchValue(Base):
    """pylti1p3's launch store, in the database so every worker sees it: nonces (used once), states, launches."""

    __tablename__ = "lti_launch_values"

    key: Mapped[str] = mapped_column(String(255), primary_key=True)
    value: Mapped[Any] = mapped_column(JSON)
    expires_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), index=True)


class LtiGradePassback(Base):
    """A grade to send to an LMS (the outbox): retried until sent; the last failure's reason is kept for the tutor."""

    __tablename__ = "lti_grade_passbacks"
    __table_args__ = (Index("ix_lti_grade_passbacks_due", "status", "next_try_at"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    # The test attempt whose mark it is; None for an exercise's mark (its line item names the exercise's test).
    attempt_id: Mapped[int | None] = mapped_column(ForeignKey("assessment_attempts.id", ondelete="CASCADE"),
                                                   index=True)
    line_item_id: Mapped[int] = mapped_column(ForeignKey("lti_line_items.id", ondelete="CASCADE"))
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    score_given: Mapped[float] = mapped_column()
    score_maximum: Mapped[float] = mapped_column()
    status: Mapped[str] = mapped_column(String(16), default="pending")  # pending | sent | superseded
    tries: Mapped[int] = mapped_column(default=0)
    next_try_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    claimed_by: Mapped[str | None] = mapped_column(String(96))
    claimed_until: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
    last_error: Mapped[str | None] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    sent_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True))
