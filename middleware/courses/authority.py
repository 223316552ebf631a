"""Who teaches what: the one answer the areas ask before a tutor acts on a course, a student or authored work.

Admins teach everything. A tutor teaches the courses they are a tutor member of, the students enrolled in
those courses, and shares the tours and lessons written by the other tutors of those courses. Students
teach nothing. Each area words its own refusal (the authorization table is in middleware/README.md).
"""

from __future__ import annotations

from sqlalchemy import Select, exists, select
from sqlalchemy.orm import Session, aliased

from middleware.accounts.services import tutors_student
from middleware.courses.services import is_course_tutor
from middleware.models import CourseMembership, Role, User


def teaches_course(session: Session, actor: User, course_id: int | None) -> bool:
    """True for an admin, and for a tutor member of the course (never for no course)."""
    if actor.role == Role.ADMIN:
        return True
    return actor.role == Role.TUTOR and course_id is not None and is_course_tutor(session, actor.id, course_id)


def teaches_student(session: Session, actor: User, target: User) -> bool:
    """True for an admin (whoever target is), and for a tutor of a course target is enrolled in as a student."""
    if actor.role == Role.ADMIN:
        return True
    return (actor.role == Role.TUTOR and target.role == Role.STUDENT
            and tutors_student(session, actor.id, target.id))


def taught_student_ids(actor: User) -> Select[int] | None:
    """The ids of the students actor teaches, as a subquery; None for an admin (everyone)."""
    if actor.role == Role.ADMIN:
        return None
    mine, theirs = aliased(CourseMembership), aliased(CourseMembership)
    taught = (select(theirs.user_id).join(mine, mine.course_id == theirs.course_id)
              .where(mine.user_id == actor.id, mine.role == "tutor", theirs.role == "student"))
    return taught  # empty for a student: nobody is a tutor member through them


def taught_course_ids(actor: User) -> Select[int]:
    """The ids of the courses actor is a tutor member of, as a subquery (an admin's own memberships only)."""
    return select(CourseMembership.course_id).where(CourseMembership.user_id == actor.id,
                                                    CourseMembership.role == "tutor")


def shares_authorship(session: Session, actor: User, author_id: int | None) -> bool:
    """True when actor may change work written by author_id: an admin, the author (a tutor), or a tutor of a
    course the author tutors too. Work with no author (the demo content) is the admins'."""
    if actor.role == Role.ADMIN:
        return True
    if actor.role != Role.TUTOR or author_id is None:
        return False
    if author_id == actor.id:
        return True
    mine, theirs = aliased(CourseMembership), aliased(CourseMembership)
    return bool(session.scalar(select(exists().where(
        mine.user_id == actor.id, mine.role == "tutor", theirs.course_id == mine.course_id,
        theirs.user_id == author_id, theirs.role == "tutor"))))
