"""Whose use an actor may read: an admin every course's (and everyone's, with no course named), a tutor the courses
they teach (the students enrolled in them), a student nothing. The one authorization rule of the analytics."""

from __future__ import annotations

from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import Refused
from middleware.models import Course, CourseMembership, Role, User


@dataclass(frozen=True)
class Scope:
    """The courses the figures cover and the students whose use they count; student_ids None: everyone's."""

    course_ids: tuple[int, ...]
    student_ids: frozenset[int] | None
    course: Course | None  # the one course named, if one was

    def covers(self, user_id: int) -> bool:
        """Whether this user's use is counted."""
        return self.student_ids is None or user_id in self.student_ids


def analyzable_courses(session: Session, actor: User) -> list[Course]:
    """The courses actor may read the analytics of (a student: none)."""
    query = select(Course).order_by(Course.code)
    if actor.role == Role.ADMIN:
        return list(session.scalars(query))
    if actor.role != Role.TUTOR:
        return []
    return list(session.scalars(query.join(CourseMembership, CourseMembership.course_id == Course.id)
                                .where(CourseMembership.user_id == actor.id, CourseMembership.role == "tutor")))


def require_analyst(actor: User) -> None:
    """403 for anyone but tutors and admins."""
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        raise Refused(403, "forbidden", gettext("Only tutors and admins read the lab's usage."))


def students_of(session: Session, course_ids: tuple[int, ...]) -> frozenset[int]:
    """The ids of the students enrolled in any of the courses."""
    if not course_ids:
        return frozenset()
    return frozenset(session.scalars(select(CourseMembership.user_id).where(
        CourseMembership.course_id.in_(course_ids), CourseMembership.role == "student")))


def resolve(session: Session, actor: User, course_id: int | None) -> Scope:
    """The scope actor asks for: one course (404 when there is none, 403 when actor does not teach it), or every
    course actor teaches (an admin: everyone)."""
    require_analyst(actor)
    if course_id is not None:
        course = session.get(Course, course_id)
        if course is None:
            raise Refused(404, "unknown_course", gettext("There is no such course."), "course_id")
        if not teaches_course(session, actor, course_id):
            raise Refused(403, "forbidden", gettext("You read the usage of the courses you teach only."),
                          "course_id")
        return Scope((course.id,), students_of(session, (course.id,)), course)
    if actor.role == Role.ADMIN:
        return Scope(tuple(c.id for c in analyzable_courses(session, actor)), None, None)
    ids = tuple(c.id for c in analyzable_courses(session, actor))
    return Scope(ids, students_of(session, ids), None)
