"""Who may change tours and lessons and run live classes: courses/authority.py's rules, worded for teaching.

A live class belongs to its course: only a tutor of that course (or an admin) starts one, and only its
leader, a tutor of its course or an admin steps, hands over (to a student of the course) or ends it; only
they and the course's students follow it (its participants' names are on its page).
Starting a class on a robot ends the class running there, so that needs the right to end it too. Only an
admin may start a class with no course, or with the override that lets it outrank the queue without a
booking (tours.with_guided_priority).
"""

from __future__ import annotations

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy.orm import Session

from middleware.courses.authority import shares_authorship, teaches_course
from middleware.courses.services import is_student_of
from middleware.errors import Refused
from middleware.models import Role, User
from middleware.models.teaching import GuidedSession


def require_author_rights(session: Session, actor: User, author_id: int | None, kind: str) -> None:
    """Refuses (403) unless actor may change this tour or lesson (kind names it in the sentence)."""
    if not shares_authorship(session, actor, author_id):
        raise Refused(403, "forbidden", gettext(
            "You can change only the tours you or another tutor of your courses wrote; save a copy under a new title "
            "instead.") if kind == "tour" else gettext(
            "You can change only the lessons you or another tutor of your courses wrote; save a copy under a new "
            "title instead."))


def may_run_class(session: Session, actor: User, live: GuidedSession) -> bool:
    """The class's leader, a tutor of its course, or an admin."""
    return live.tutor_id == actor.id or teaches_course(session, actor, live.course_id)


def may_follow_class(session: Session, user: User, live: GuidedSession) -> bool:
    """Who may follow a class (its page, its state, its channel): whoever may run it and the students of its
    course; an admin's class with no course, anyone logged in."""
    return (live.course_id is None or may_run_class(session, user, live)
            or is_student_of(session, user.id, live.course_id))


def require_class_follower(session: Session, user: User, live: GuidedSession) -> None:
    """Refuses (403) anyone who may not follow this class."""
    if not may_follow_class(session, user, live):
        raise Refused(403, "not_in_course", gettext("This class is for the students of another course."), "session_id")


def require_class_rights(session: Session, actor: User, live: GuidedSession) -> None:
    """Refuses (403) anyone who may not step, hand over or end this class."""
    if not may_run_class(session, actor, live):
        raise Refused(403, "not_tutor", gettext("Only the tutors of this class's course can do that."))


def require_class_member(session: Session, live: GuidedSession, user: User) -> None:
    """Refuses (403) handing a course's class robot to anyone but a student of that course (a class with no
    course, an admin's, may hand it to anyone)."""
    if live.course_id is not None and not is_student_of(session, user.id, live.course_id):
        raise Refused(403, "forbidden", gettext("%(username)s is not a student of this class's course, so the robot "
                                                "cannot be handed to them.", username=user.username), "user")


def check_class_start(session: Session, actor: User, course_id: int | None, override: bool,
                      running: GuidedSession | None) -> None:
    """Refuses a class start actor may not make: a course they do not teach, no course or an override (admins
    only), or a robot where a class they may not end is running (409)."""
    if course_id is None and actor.role != Role.ADMIN:
        raise Refused(403, "forbidden", gettext("Choose a course you teach: a class is led for one course."),
                                        "course_id")
    if course_id is not None and not teaches_course(session, actor, course_id):
        raise Refused(403, "forbidden", gettext("You can lead classes only for the courses you teach."), "course_id")
    if override and actor.role != Role.ADMIN:
        raise Refused(403, "forbidden", gettext("Only an admin can let a class go before the queue without a "
                                                "booking; book a class slot on the robot instead."), "override")
    if running is not None and not may_run_class(session, actor, running):
        raise Refused(409, "class_running", gettext("Another course's class is running on this robot; choose "
                                                    "another robot or wait until that class ends."), "robot")
