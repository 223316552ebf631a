"""Teaching: tours (fully guided or run live by a tutor), their live sessions, and video lessons."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import DateTime, ForeignKey, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class Tour(Base):
    """A tour: ordered steps (text, panel, optional skill with parameters, condition) kept as checked JSON."""

    __tablename__ = "tours"

    id: Mapped[int] = mapped_column(primary_key=True)
    slug: Mapped[str] = mapped_column(String(64), unique=True)
    title: Mapped[str] = mapped_column(String(120))
    summary: Mapped[str] = mapped_column(String(500), default="")
    topics: Mapped[str] = mapped_column(Text, default="", server_default="")  # "a, b": lower-case, for recommendations
    steps_json: Mapped[str] = mapped_column(Text)
    author_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class GuidedSession(Base):
    """A live class: a tutor leads a tour on a lab robot; students follow; control may be handed to one."""

    __tablename__ = "guided_sessions"

    id: Mapped[int] = mapped_column(primary_key=True)
    tour_id: Mapped[int] = mapped_column(ForeignKey("tours.id", ondelete="CASCADE"), index=True)
    robot_name: Mapped[str] = mapped_column(String(64), index=True)
    tutor_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    course_id: Mapped[int | None] = mapped_column(ForeignKey("courses.id", ondelete="SET NULL"), nullable=True)
    step_index: Mapped[int] = mapped_column(Integer, default=0)
    # Who has the robot first while the session runs: the tutor, or the student the tutor handed control to.
    control_user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    # The admin who let this class outrank the queue without a booking; None: only the leader's booked slot does.
    priority_override_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"),
                                                                nullable=True)
    version: Mapped[int] = mapped_column(Integer, default=0)
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    ended_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)


class GuidedSessionPresence(Base):
    """One open page of a live class (a socket, in whichever worker): its user is present while it is heard."""

    __tablename__ = "guided_session_presence"

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("guided_sessions.id", ondelete="CASCADE"), index=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    socket_key: Mapped[str] = mapped_column(String(96), unique=True)
    heard_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class Lesson(Base):
    """A video lesson: a video file of the lessons folder and its checked cue track (canonical WebVTT)."""

    __tablename__ = "lessons"

    id: Mapped[int] = mapped_column(primary_key=True)
    slug: Mapped[str] = mapped_column(String(64), unique=True)
    title: Mapped[str] = mapped_column(String(120))
    summary: Mapped[str] = mapped_column(String(500), default="")
    topics: Mapped[str] = mapped_column(Text, default="", server_default="")  # "a, b": lower-case, for recommendations
    video_name: Mapped[str] = mapped_column(String(128))
    cues_vtt: Mapped[str] = mapped_column(Text)
    # The comprehension test taken before the video (required: its cues wait for it) and after it.
    before_exam_id: Mapped[int | None] = mapped_column(ForeignKey("assessment_exams.id", ondelete="SET NULL"),
                                                       nullable=True)
    after_exam_id: Mapped[int | None] = mapped_column(ForeignKey("assessment_exams.id", ondelete="SET NULL"),
                                                      nullable=True)
    author_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
