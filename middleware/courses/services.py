"""Course rules: who creates and manages courses, enrolment one by one and from CSV. No Flask request state.

Tutors and admins create courses; the tutor who creates one becomes its tutor. A course is managed by
its tutor members and by admins, nobody else. Only student accounts are enrolled as students. The
caller commits.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from middleware.accounts.services import forbidden, is_course_tutor
from middleware.auth.schemas import InvalidField, clean_username
from middleware.auth.services import create_user, generate_password
from middleware.courses.schemas import CourseSettings, clean_code, clean_title, parse_enrolment_csv
from middleware.errors import Refused
from middleware.i18n import role_name
from middleware.models import Course, CourseMembership, Role, User
from middleware.models.courses import (
    DEFAULT_BOOKING_ALLOWANCE_MIN,
    DEFAULT_GRADED_RUN_HOLD_MIN,
    DEFAULT_TURN_LENGTH_S,
)


@dataclass(frozen=True)
class CourseView:
    """A course as lists and the API show it."""

    id: int
    code: str
    title: str
    turn_length_s: int
    booking_allowance_min: int
    graded_run_hold_min: int
    students: int
    students_set_velocity: bool
    students_set_watchdog: bool
    my_role: str | None  # the viewer's membership role, None for an admin who is not a member

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"id": self.id, "code": self.code, "title": self.title, "turn_length_s": self.turn_length_s,
                "booking_allowance_min": self.booking_allowance_min,
                "graded_run_hold_min": self.graded_run_hold_min, "students": self.students,
                "my_role": self.my_role, "students_set_velocity": self.students_set_velocity,
                "students_set_watchdog": self.students_set_watchdog}


@dataclass(frozen=True)
class MemberView:
    """A member of a course."""

    user_id: int
    username: str
    role: str  # membership role
    is_active: bool

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"user_id": self.user_id, "username": self.username, "role": self.role, "is_active": self.is_active}


def get_course(session: Session, course_id: int) -> Course:
    """The course with that id, or a 404 refusal."""
    course = session.get(Course, course_id)
    if course is None:
        raise Refused(404, "unknown_course", gettext("There is no course with id %(course_id)s.", course_id=course_id),
                                             "course_id")
    return course


def is_student_of(session: Session, user_id: int, course_id: int) -> bool:
    """True when user_id is enrolled as a student of the course."""
    return session.scalar(select(CourseMembership.id).where(
        CourseMembership.course_id == course_id, CourseMembership.user_id == user_id,
        CourseMembership.role == "student")) is not None


def managed_course(session: Session, actor: User, course_id: int) -> Course:
    """The course, when actor may manage it (a tutor member, or an admin); 404 or 403 otherwise."""
    course = get_course(session, course_id)
    if actor.role == Role.ADMIN or (actor.role == Role.TUTOR and is_course_tutor(session, actor.id, course.id)):
        return course
    raise forbidden(gettext("You can manage only the courses you teach."))


def _views(session: Session, courses: list[Course], actor: User) -> list[CourseView]:
    ids = [c.id for c in courses]
    counts = dict(session.execute(
        select(CourseMembership.course_id, func.count()).where(
            CourseMembership.course_id.in_(ids), CourseMembership.role == "student")
        .group_by(CourseMembership.course_id)).all()) if ids else {}
    roles = dict(session.execute(select(CourseMembership.course_id, CourseMembership.role).where(
        CourseMembership.course_id.in_(ids), CourseMembership.user_id == actor.id)).all()) if ids else {}
    return [CourseView(c.id, c.code, c.title, c.turn_length_s, c.booking_allowance_min, c.graded_run_hold_min,
                       counts.get(c.id, 0), c.students_set_velocity, c.students_set_watchdog,
                       roles.get(c.id)) for c in courses]


def list_courses(session: Session, actor: User) -> list[CourseView]:
    """Courses the actor belongs to (as student or tutor); every course for an admin."""
    query = select(Course).order_by(Course.code)
    if actor.role != Role.ADMIN:
        query = query.join(CourseMembership, CourseMembership.course_id == Course.id).where(
            CourseMembership.user_id == actor.id)
    return _views(session, list(session.scalars(query)), actor)


def describe(session: Session, actor: User, course: Course) -> CourseView:
    """One course as a CourseView."""
    return _views(session, [course], actor)[0]


def create_course(session: Session, actor: User, code: object, title: object, settings: CourseSettings) -> Course:
    """A new course (tutors and admins); a tutor creator becomes its tutor."""
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        raise forbidden(gettext("Only tutors and admins can create courses."))
    clean = clean_code(code)
    course = Course(code=clean, title=clean_title(title),
                    turn_length_s=settings.turn_length_s or DEFAULT_TURN_LENGTH_S,
                    booking_allowance_min=(DEFAULT_BOOKING_ALLOWANCE_MIN if settings.booking_allowance_min is None
                                           else settings.booking_allowance_min),
                    graded_run_hold_min=settings.graded_run_hold_min or DEFAULT_GRADED_RUN_HOLD_MIN)
    if session.scalar(select(Course.id).where(Course.code == clean)) is not None:
        raise Refused(409, "course_exists", gettext("A course with code %(clean)s exists already; choose another "
                                                    "code.", clean=clean), "code")
    session.add(course)
    session.flush()
    if actor.role == Role.TUTOR:
        session.add(CourseMembership(course_id=course.id, user_id=actor.id, role="tutor"))
        session.flush()
    return course


def update_settings(session: Session, actor: User, course_id: int, settings: CourseSettings) -> Course:
    """Changes a course's title, turn length, booking allowance or graded run hold (its tutors, admins)."""
    course = managed_course(session, actor, course_id)
    if settings.title is not None:
        course.title = settings.title
    if settings.turn_length_s is not None:
        course.turn_length_s = settings.turn_length_s
    if settings.booking_allowance_min is not None:
        course.booking_allowance_min = settings.booking_allowance_min
    if settings.graded_run_hold_min is not None:
        course.graded_run_hold_min = settings.graded_run_hold_min
    if settings.students_set_velocity is not None:
        course.students_set_velocity = settings.students_set_velocity
    if settings.students_set_watchdog is not None:
        course.students_set_watchdog = settings.students_set_watchdog
    return course


def members(session: Session, actor: User, course_id: int) -> list[MemberView]:
    """The course's tutors then students, by username (its tutors, admins)."""
    managed_course(session, actor, course_id)
    rows = session.execute(
        select(User.id, User.username, CourseMembership.role, User.is_active)
        .join(CourseMembership, CourseMembership.user_id == User.id)
        .where(CourseMembership.course_id == course_id)
        .order_by(CourseMembership.role.desc(), User.username))
    return [MemberView(*row) for row in rows]


def _refusal_to_enrol(session: Session, course_id: int, user: User) -> str | None:
    """Why user cannot be enrolled as a student of the course, or None."""
    if user.role != Role.STUDENT:
        return str(gettext("%(username)s is a %(role)s account; only student accounts are enrolled as students.",
                           username=user.username, role=role_name(user.role)))
    if not user.is_active:
        return str(gettext("%(username)s's account is disabled; an admin can enable it.", username=user.username))
    already = session.scalar(select(CourseMembership.role).where(
        CourseMembership.course_id == course_id, CourseMembership.user_id == user.id))
    if already is not None:
        return str(gettext("%(username)s is already enrolled in this course.", username=user.username))
    return None


def enrol(session: Session, actor: User, course_id: int, username: object) -> User:
    """Enrols an existing student account by username (its tutors, admins)."""
    course = managed_course(session, actor, course_id)
    name = clean_username(username)
    user = session.scalar(select(User).where(User.username == name))
    if user is None:
        raise Refused(404, "unknown_user", gettext("There is no account named %(name)s. Check the spelling, or "
                                                   "upload a CSV file to create accounts.", name=repr(name)),
                      "username")
    reason = _refusal_to_enrol(session, course.id, user)
    if reason is not None:
        raise Refused(409, "not_enrolled", reason, "username")
    session.add(CourseMembership(course_id=course.id, user_id=user.id, role="student"))
    session.flush()
    return user


def unenrol(session: Session, actor: User, course_id: int, user_id: int) -> None:
    """Removes a student from the course (its tutors, admins); tutors are not removed here."""
    course = managed_course(session, actor, course_id)
    membership = session.scalar(select(CourseMembership).where(
        CourseMembership.course_id == course.id, CourseMembership.user_id == user_id))
    if membership is None or membership.role != "student":
        raise Refused(404, "not_a_student", gettext("That account is not a student of this course."), "user_id")
    session.delete(membership)
    session.flush()


@dataclass
class EnrolmentReport:
    """What a CSV upload did: accounts enrolled, accounts created (password shown once), rows refused."""

    enrolled: list[str] = field(default_factory=list)
    created: list[tuple[str, str]] = field(default_factory=list)  # (username, generated password)
    refused: list[tuple[int, str, str]] = field(default_factory=list)  # (line, value as written, reason)

    def to_dict(self) -> dict[str, object]:
        """The JSON form (the passwords are in it: it is shown once to the tutor who uploaded)."""
        return {"enrolled": self.enrolled,
                "created": [{"username": u, "password": p} for u, p in self.created],
                "refused": [{"line": n, "value": v, "reason": r} for n, v, r in self.refused]}


def enrol_from_csv(session: Session, actor: User, course_id: int, data: bytes) -> EnrolmentReport:
    """Enrols existing students named in the file, creates student accounts for new names; reports the rest.

    A file that cannot be read at all (encoding, header, size) raises InvalidField("file") and changes nothing.
    """
    course = managed_course(session, actor, course_id)
    rows = parse_enrolment_csv(data)
    report = EnrolmentReport()
    seen: dict[str, int] = {}
    for row in rows:
        if row.empty or not row.username:
            report.refused.append((row.line, row.username, gettext("The row has no username.")))
            continue
        try:
            name = clean_username(row.username)
        except InvalidField as invalid:
            report.refused.append((row.line, row.username, invalid.message))
            continue
        if name in seen:
            report.refused.append((row.line, row.username, gettext(
                "%(name)s appears earlier in the file (line %(line)s).", name=name, line=seen[name])))
            continue
        seen[name] = row.line
        user = session.scalar(select(User).where(User.username == name))
        if user is None:
            password = generate_password()
            user = create_user(session, name, Role.STUDENT, password)
            report.created.append((name, password))
        else:
            reason = _refusal_to_enrol(session, course.id, user)
            if reason is not None:
                report.refused.append((row.line, row.username, reason))
                continue
            report.enrolled.append(name)
        session.add(CourseMembership(course_id=course.id, user_id=user.id, role="student"))
        session.flush()
    return report
