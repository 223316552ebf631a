"""The LTI area wired into an app: framing origins, the grade sender, and the course page's LMS panel."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from flask import Flask
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.db import get_session
from middleware.lti import embedding, services
from middleware.lti.grades import GradeSender
from middleware.lti.roster import linked_context
from middleware.models import User
from middleware.models.assessment import Exam
from middleware.models.exercises import Exercise, ExerciseAssignment
from middleware.models.lti import LtiGradePassback, LtiLineItem

_SENDER_KEY = "telelab.lti.grade_sender"


@dataclass(frozen=True)
class WaitingGrade:
    """A grade the LMS has not taken yet, as the tutor reads it."""

    username: str
    column: str
    score: str
    tries: int
    next_try_at: datetime
    reason: str | None


@dataclass(frozen=True)
class GradebookColumn:
    """A line item of the LMS course (a placed test, or an exercise that is a test of the course): grades sent to it
    and grades waiting."""

    title: str
    kind: str
    sent: int
    waiting: int


@dataclass(frozen=True)
class CoursePanel:
    """The course page's LMS card: roster sync, and grades sent and waiting."""

    roster_synced_at: datetime | None
    has_roster_service: bool
    sent: int
    columns: list[GradebookColumn]
    waiting: list[WaitingGrade]


def _column_titles(session: Session, context_id: int) -> dict[int, tuple[str, str]]:
    """line item id -> (what it grades, its kind), for the context's line items."""
    tests = session.execute(select(LtiLineItem.id, Exam.title).join(Exam, Exam.id == LtiLineItem.exam_id)
                            .where(LtiLineItem.context_id == context_id)).all()
    exercises = session.execute(select(LtiLineItem.id, Exercise.title)
                                .join(ExerciseAssignment, ExerciseAssignment.id == LtiLineItem.exercise_assignment_id)
                                .join(Exercise, Exercise.id == ExerciseAssignment.exercise_id)
                                .where(LtiLineItem.context_id == context_id)).all()
    return {**{item: (title, str(gettext("Test"))) for item, title in tests},
            **{item: (title, str(gettext("Python exercise"))) for item, title in exercises}}


def course_panel(course_id: int) -> CoursePanel | None:
    """The LMS card of a course linked to an LMS course, for its tutors (None otherwise)."""
    if not current_user.is_authenticated:
        return None
    session = get_session()
    context = linked_context(session, course_id)
    if context is None or not teaches_course(session, current_user, course_id):
        return None
    titles = _column_titles(session, context.id)
    rows = session.execute(select(LtiGradePassback, User.username).join(User, User.id == LtiGradePassback.user_id)
                           .where(LtiGradePassback.line_item_id.in_(list(titles)),
                                  LtiGradePassback.status.in_(("pending", "sent")))
                           .order_by(LtiGradePassback.id.desc())).all()
    waiting = [WaitingGrade(name, titles[row.line_item_id][0], f"{row.score_given:g} / {row.score_maximum:g}",
                            row.tries, row.next_try_at, services.said(row.last_error) if row.last_error else None)
               for row, name in rows if row.status == "pending"]
    columns = [GradebookColumn(title, kind, sum(1 for row, _ in rows if row.line_item_id == item
                                                and row.status == "sent"),
                               sum(1 for row, _ in rows if row.line_item_id == item and row.status == "pending"))
               for item, (title, kind) in sorted(titles.items(), key=lambda entry: (entry[1][1], entry[1][0]))]
    return CoursePanel(context.roster_synced_at, bool(context.memberships_url),
                       sum(1 for row, _ in rows if row.status == "sent"), columns, waiting)


def init_app(app: Flask) -> GradeSender:
    """Installs the area's per-app parts; the grade sender is returned for create_app to stop with the app."""
    embedding.init_app(app)
    sender = GradeSender(app)
    app.extensions[_SENDER_KEY] = sender
    app.before_request(sender.maybe_wake)
    app.add_template_global(course_panel, "lti_course_panel")
    return sender
