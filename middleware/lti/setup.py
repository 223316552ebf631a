"""The LTI area wired into an app: framing origins, the grade sender, and the course page's LMS panel."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from flask import Flask
from flask_login import current_user
from sqlalchemy import select

from middleware.courses.authority import teaches_course
from middleware.db import get_session
from middleware.lti import embedding, services
from middleware.lti.grades import GradeSender
from middleware.lti.roster import linked_context
from middleware.models import User
from middleware.models.lti import LtiGradePassback, LtiLineItem

_SENDER_KEY = "telelab.lti.grade_sender"


@dataclass(frozen=True)
class WaitingGrade:
    """A grade the LMS has not taken yet, as the tutor reads it."""

    username: str
    score: str
    tries: int
    next_try_at: datetime
    reason: str | None


@dataclass(frozen=True)
class CoursePanel:
    """The course page's LMS card: roster sync, and grades sent and waiting."""

    roster_synced_at: datetime | None
    has_roster_service: bool
    sent: int
    waiting: list[WaitingGrade]


def course_panel(course_id: int) -> CoursePanel | None:
    """The LMS card of a course linked to an LMS course, for its tutors (None otherwise)."""
    if not current_user.is_authenticated:
        return None
    session = get_session()
    context = linked_context(session, course_id)
    if context is None or not teaches_course(session, current_user, course_id):
        return None
    items = select(LtiLineItem.id).where(LtiLineItem.context_id == context.id)
    rows = session.execute(select(LtiGradePassback, User.username).join(User, User.id == LtiGradePassback.user_id)
                           .where(LtiGradePassback.line_item_id.in_(items),
                                  LtiGradePassback.status.in_(("pending", "sent")))
                           .order_by(LtiGradePassback.id.desc())).all()
    waiting = [WaitingGrade(name, f"{row.score_given:g} / {row.score_maximum:g}", row.tries, row.next_try_at,
                            services.said(row.last_error) if row.last_error else None)
               for row, name in rows if row.status == "pending"]
    return CoursePanel(context.roster_synced_at, bool(context.memberships_url),
                       sum(1 for row, _ in rows if row.status == "sent"), waiting)


def init_app(app: Flask) -> GradeSender:
    """Installs the area's per-app parts; the grade sender is returned for create_app to stop with the app."""
    embedding.init_app(app)
    sender = GradeSender(app)
    app.extensions[_SENDER_KEY] = sender
    app.before_request(sender.maybe_wake)
    app.add_template_global(course_panel, "lti_course_panel")
    return sender
