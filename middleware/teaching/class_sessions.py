"""Class sessions: a tutor opens the lab for a course, and every enrolled student gets a robot of their own.

Starting a session writes it and one seat per student, then starts every student's practice robot on the
farm at once (in the background, a few at a time), so that the first student to open the class page waits
no longer than the last. A seat records how its robot's start went (starting, ready, failed with the reason),
so every worker shows the same page. Robots of an open session are not stopped as idle; ending the session
stops them. What students did stays in the database: ending stops robots, it deletes nothing.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.courses.services import get_course, managed_course
from middleware.errors import Refused
from middleware.i18n import N_
from middleware.models import Course, CourseMembership, User
from middleware.models.accounts import utc_now
from middleware.models.farm import ClassSeat, ClassSession, PersonalRobotRecord
from middleware.models.lab import ResponseTimeReport
from middleware.teaching.practice_robots import PracticeManager, practice_name

STARTS_AT_ONCE = 8  # robots started in parallel: enough to fill a host's cores, few enough to share them
# The scenes a class may run: the lab arena (lessons, tours, most tests) or a course of the delay experiment.
# Their titles are marked for the catalogue; the page says them in its language.
CLASS_SCENES = {"lab": N_("The lab arena"), "course-A": N_("Course A of the delay experiment"),
                "course-B": N_("Course B of the delay experiment")}
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SeatView:
    """A student's seat as the tutor's page shows it."""

    user_id: int
    username: str
    state: str
    message: str
    robot: str
    response_times: dict[str, Any] | None = None  # what the student's console measured on the robot

    def to_dict(self) -> dict[str, object]:
        """The seat as JSON."""
        return {"user_id": self.user_id, "username": self.username, "state": self.state, "message": self.message,
                "robot": self.robot, "response_times": self.response_times}


def open_session(session: Session, course_id: int) -> ClassSession | None:
    """The course's open class session, if there is one."""
    return session.scalar(select(ClassSession).where(ClassSession.course_id == course_id,
                                                     ClassSession.ended_at.is_(None)))


def clean_scene(value: object) -> str:
    """The scene a tutor chose for a class session ("lab" when none); a 400 naming the field otherwise."""
    if value in (None, ""):
        return "lab"
    if not isinstance(value, str) or value not in CLASS_SCENES:
        raise Refused(400, "invalid_field", gettext("scene must be one of %(scenes)s.", scenes=", ".join(CLASS_SCENES)),
                      "scene")
    return value


def class_robot(session: Session, course_id: int, user_id: int) -> PersonalRobotRecord | None:
    """The student's own running robot in the course's open class session, if there is one."""
    return session.scalar(select(PersonalRobotRecord).join(
        ClassSession, ClassSession.id == PersonalRobotRecord.class_session_id).where(
        ClassSession.course_id == course_id, ClassSession.ended_at.is_(None), PersonalRobotRecord.owner_id == user_id,
        PersonalRobotRecord.address != ""))


def start_session(session: Session, actor: User, course_id: int, manager: PracticeManager,
                  scene: str = "lab", booking_id: int | None = None) -> ClassSession:
    """Opens a class session for the course (its tutors and admins only) with a seat per enrolled student, every
    student's robot running scene.

    Refused when one is open already (409), when the course has no student (409), when the farm cannot hold
    one robot per student beside those running (409), or cannot be reached (503); nothing is written then.
    """
    course = managed_course(session, actor, course_id)
    if open_session(session, course.id) is not None:
        raise Refused(409, "class_session_open", gettext("A class session is open for this course already; end it "
                                                         "first."))
    students = _students(session, course)
    if not students:
        raise Refused(409, "no_students", gettext("The course has no enrolled student yet; enrol the class first."))
    free = manager.limit() - manager.count()
    running = set(session.scalars(select(PersonalRobotRecord.owner_id).where(
        PersonalRobotRecord.owner_id.in_([user.id for user in students]))))
    needed = len(students) - len(running)
    if needed > free:
        raise Refused(409, "farm_full", gettext("The robot farm can start %(free)s more robots now and the class needs "
                                                "%(needed)s. Ask an administrator to add a robot host, or try again "
                                                "when other classes have ended.", free=max(free, 0), needed=needed))
    opened = ClassSession(course_id=course.id, started_by_id=actor.id, scene=scene, booking_id=booking_id)
    session.add(opened)
    try:
        session.flush()
    except IntegrityError:  # another tutor opened it at the same moment; the unit of work's owner rolls back
        raise Refused(409, "class_session_open", lazy_gettext("A class session is open for this course already.")) \
            from None
    session.add_all(ClassSeat(session_id=opened.id, user_id=user.id) for user in students)
    session.flush()
    return opened


def prestart_robots(sessions: Callable[[], Session], manager: PracticeManager, class_session_id: int,
                    only_user_id: int | None = None) -> None:
    """Starts every seat's robot (or only_user_id's) in the background, a few at a time, recording each outcome on
    its seat."""
    threading.Thread(target=start_robots, args=(sessions, manager, class_session_id, only_user_id),
                     name=f"class-{class_session_id}-start", daemon=True).start()


def start_robots(sessions: Callable[[], Session], manager: PracticeManager, class_session_id: int,
                 only_user_id: int | None = None) -> None:
    """Starts every starting seat's robot (or only_user_id's), a few at a time, recording each outcome on its seat;
    returns once every start ended."""
    with sessions() as session:
        query = (select(ClassSeat.user_id, User.username).join(User, User.id == ClassSeat.user_id)
                 .where(ClassSeat.session_id == class_session_id))
        if only_user_id is not None:
            query = query.where(ClassSeat.user_id == only_user_id)
        seats = session.execute(query).all()
        scene = session.scalar(select(ClassSession.scene).where(ClassSession.id == class_session_id)) or "lab"

    def start_one(user_id: int, username: str) -> None:
        try:
            manager.start(user_id, username, class_session_id=class_session_id, scene=scene)
            state, message = "ready", ""
        except Refused as refusal:
            state, message = "failed", refusal.message
        except Exception:  # noqa: BLE001 - one student's robot must not stop the others'
            log.exception("class session %s: the robot of %s did not start", class_session_id, username)
            state, message = "failed", NOT_STARTED
        _set_seat(sessions, class_session_id, user_id, state, message)

    with ThreadPoolExecutor(STARTS_AT_ONCE, thread_name_prefix=f"class-{class_session_id}") as pool:
        for user_id, username in seats:
            pool.submit(start_one, user_id, username)


def restart_my_robot(session: Session, actor: User) -> int:
    """Marks the actor's seat starting again when their class robot no longer runs (they stopped it, or it was
    lost); the class session's id, whose robot the caller starts once this is committed. 409 while it runs."""
    found = my_seat(session, actor)
    if found is None:
        raise Refused(409, "no_class_session", gettext("No class session is open for your courses now."))
    _course, seat = found
    if live_state(seat.state, _robot_runs(session, seat.session_id, actor.id)) in ("starting", "ready"):
        raise Refused(409, "robot_running", gettext("Your robot is running or starting already."))
    seat.state, seat.message, seat.updated_at = "starting", "", utc_now()
    session.flush()
    return seat.session_id


def end_session(session: Session, actor: User, course_id: int) -> list[int]:
    """Ends the course's open session and marks its seats stopped; the owners whose robots the caller stops once
    this is committed."""
    course = managed_course(session, actor, course_id)
    opened = open_session(session, course.id)
    if opened is None:
        raise Refused(409, "no_class_session", gettext("No class session is open for this course."))
    opened.ended_at = utc_now()
    owners = session.scalars(select(PersonalRobotRecord.owner_id).where(
        PersonalRobotRecord.class_session_id == opened.id)).all()
    session.execute(update(ClassSeat).where(ClassSeat.session_id == opened.id)
                    .values(state="stopped", message="", updated_at=utc_now()))
    return list(owners)


STOPPED_WHILE_OPEN = N_("The robot was stopped; the student can start it again from their class page.")
NOT_STARTED = N_("The robot did not start; the tutor can start the session again.")


def seat_message(stored: str) -> str:
    """A seat's stored sentence in the reader's language: a seat's robot starts on a thread with no request, so its
    outcome is stored in English, and a sentence of the catalogue is said again here (one with values in it stays
    as stored)."""
    return gettext(stored) if stored else ""


def live_state(stored: str, running: bool) -> str:
    """A seat's state as it is now: a seat whose robot started but runs no more (its student stopped it, or the
    farm lost it) is stopped, whatever its start recorded."""
    return "stopped" if stored == "ready" and not running else stored


def _running_owners(session: Session, class_session_id: int) -> set[int]:
    return set(session.scalars(select(PersonalRobotRecord.owner_id).where(
        PersonalRobotRecord.class_session_id == class_session_id, PersonalRobotRecord.address != "")))


def _robot_runs(session: Session, class_session_id: int, user_id: int) -> bool:
    return user_id in _running_owners(session, class_session_id)


def seats(session: Session, actor: User, course_id: int) -> tuple[ClassSession | None, list[SeatView]]:
    """The course's open session and its seats as they are now, for its tutors and admins."""
    course = managed_course(session, actor, course_id)
    opened = open_session(session, course.id)
    if opened is None:
        return None, []
    rows = session.execute(select(ClassSeat, User.username).join(User, User.id == ClassSeat.user_id)
                           .where(ClassSeat.session_id == opened.id).order_by(User.username)).all()
    running = _running_owners(session, opened.id)
    robots = {seat.user_id: practice_name(username, seat.user_id) for seat, username in rows}
    measured = _response_times(session, robots)
    views = []
    for seat, username in rows:
        state = live_state(seat.state, seat.user_id in running)
        message = gettext(STOPPED_WHILE_OPEN) if state != seat.state else seat_message(seat.message)
        views.append(SeatView(seat.user_id, username, state, message, robots[seat.user_id],
                              measured.get(seat.user_id)))
    return opened, views


def _response_times(session: Session, robots: dict[int, str]) -> dict[int, dict[str, Any]]:
    """Each student's latest response-time figures on their class robot (user id -> figures), in one read."""
    if not robots:
        return {}
    reports = session.scalars(select(ResponseTimeReport).where(ResponseTimeReport.user_id.in_(robots)))
    return {report.user_id: report.figures for report in reports if robots.get(report.user_id) == report.robot_name}


def my_seat(session: Session, actor: User) -> tuple[Course, ClassSeat] | None:
    """The open class session the user has a seat in (the most recent), with its course."""
    row = session.execute(select(ClassSeat, ClassSession.course_id).join(ClassSession)
                          .where(ClassSeat.user_id == actor.id, ClassSession.ended_at.is_(None))
                          .order_by(ClassSession.started_at.desc())).first()
    if row is None:
        return None
    seat, course_id = row
    return get_course(session, course_id), seat


def my_seat_state(session: Session, actor: User, seat: ClassSeat) -> str:
    """The actor's seat's state as it is now (see live_state)."""
    return live_state(seat.state, _robot_runs(session, seat.session_id, actor.id))


def _students(session: Session, course: Course) -> list[User]:
    return list(session.scalars(select(User).join(CourseMembership, CourseMembership.user_id == User.id).where(
        CourseMembership.course_id == course.id, CourseMembership.role == "student", User.is_active.is_(True))
        .order_by(User.username)))


def _set_seat(sessions: Callable[[], Session], class_session_id: int, user_id: int, state: str, message: str) -> None:
    with sessions() as session:
        session.execute(update(ClassSeat).where(ClassSeat.session_id == class_session_id, ClassSeat.user_id == user_id,
                                                ClassSeat.state == "starting")
                        .values(state=state, message=message[:300], updated_at=utc_now()))
        session.commit()
