"""Who may do what in assessment: a course's tutors and admins manage it; its students take its exams."""

from __future__ import annotations

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy.orm import Session

from middleware.accounts.services import forbidden
from middleware.courses.services import get_course, is_student_of, managed_course
from middleware.errors import Refused
from middleware.models import Course, Role, User
from middleware.models.assessment import Attempt, Exam


def teaching_course(session: Session, actor: User, course_id: int) -> Course:
    """The course when actor teaches it or is an admin; 404 or 403 otherwise."""
    return managed_course(session, actor, course_id)


def student_course(session: Session, actor: User, course_id: int) -> Course:
    """The course when actor is one of its students; 404 or 403 otherwise."""
    course = get_course(session, course_id)
    if actor.role != Role.STUDENT or not is_student_of(session, actor.id, course_id):
        raise forbidden(gettext("Only the students of this course can do that."))
    return course


def get_exam(session: Session, exam_id: int) -> Exam:
    """The exam, or a 404 refusal."""
    exam = session.get(Exam, exam_id)
    if exam is None:
        raise Refused(404, "unknown_exam", gettext("There is no test with id %(exam_id)s.", exam_id=exam_id), "exam_id")
    return exam


def get_attempt(session: Session, attempt_id: int) -> Attempt:
    """The attempt, or a 404 refusal."""
    attempt = session.get(Attempt, attempt_id)
    if attempt is None:
        raise Refused(404, "unknown_attempt", gettext("There is no attempt with id %(attempt_id)s.",
                                                      attempt_id=attempt_id), "attempt_id")
    return attempt


def may_teach(session: Session, actor: User, course_id: int) -> bool:
    """True when actor teaches the course or is an admin."""
    try:
        managed_course(session, actor, course_id)
    except Refused:
        return False
    return True


def readable_attempt(session: Session, actor: User, attempt_id: int) -> tuple[Attempt, Exam]:
    """The attempt when actor owns it or teaches its course; 403 otherwise (other students included)."""
    attempt = get_attempt(session, attempt_id)
    exam = get_exam(session, attempt.exam_id)
    if attempt.user_id == actor.id or may_teach(session, actor, exam.course_id):
        return attempt, exam
    raise forbidden(gettext("You can open only your own attempts."))
