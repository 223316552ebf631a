"""The demo class: `telelab up` shows the class wall with a class in session (issue 31).

The demo tutor's course (middleware/demo_course.py) gets three active demo pupils beside the demo student, and a
class session open on the lab scene, opened through the class sessions' own rules: every seat's robot started on the
farm, one pupil's hand raised with a question, and a line in the class chat. All of it once: the pupils' accounts
mark the seed as done, and a later start only starts the robots of the demo class again when the tutor has not
ended it (the farm's robots end with the lab). The tests' apps never call it (it starts robots): only the launcher
does, through `lab_runner.seed_demo_content`.
"""

from __future__ import annotations

import logging
from datetime import UTC, datetime

from flask import Flask
from sqlalchemy import select, update
from sqlalchemy.orm import Session, sessionmaker

from middleware.auth.services import create_user, find_user, generate_password
from middleware.chat.services import post_message
from middleware.courses import services as courses
from middleware.db import session_factory
from middleware.demo_course import DEMO_COURSE_CODE
from middleware.errors import Refused
from middleware.models import Course, Role, User
from middleware.models.farm import ClassSeat, PersonalRobotRecord
from middleware.teaching import class_sessions, class_wall
from middleware.teaching.class_wall_live import chat_room
from middleware.teaching.practice_robots import PracticeManager, practice_manager

log = logging.getLogger(__name__)
DEMO_PUPILS = ("demo-pupil-1", "demo-pupil-2", "demo-pupil-3")
DEMO_HAND = ("demo-pupil-2", "My robot stops in front of the crate: is the sonar too careful?")
DEMO_CHAT = (("demo-pupil-1", "Has anyone's robot reached the far wall yet?"),
             ("demo-pupil-3", "Mine did: drive slowly near the crates, the collision guard stops it otherwise."))


def seed_demo_class(app: Flask) -> list[str]:
    """Opens the demo class (robots, a raised hand, the class chat) once, or starts its robots again; what it did."""
    sessions = session_factory(app)
    manager = practice_manager(app)
    try:
        with sessions() as session, session.begin():
            tutor = find_user(session, "tutor")
            course_id = session.scalar(select(Course.id).where(Course.code == DEMO_COURSE_CODE))
            if tutor is None or tutor.role != Role.TUTOR or course_id is None:
                return []
            seeded = find_user(session, DEMO_PUPILS[0]) is not None
            opened = class_sessions.open_session(session, course_id)
            if not seeded:
                for name in DEMO_PUPILS:
                    create_user(session, name, Role.STUDENT, generate_password())
                    courses.enrol(session, tutor, course_id, name)
                opened = class_sessions.start_session(session, tutor, course_id, manager, "lab")
            class_session_id = None if opened is None else opened.id
    except Refused as refused:  # the farm cannot hold the class: the lab starts without it (and tries next time)
        log.warning("no demo class: %s", refused.message)
        return []
    if class_session_id is None:
        return []  # the tutor ended the demo class: it stays ended
    if seeded:
        return _restart_robots(sessions, manager, class_session_id)
    class_sessions.start_robots(sessions, manager, class_session_id)
    with sessions() as session, session.begin():
        class_wall.raise_hand(session, _account(session, DEMO_HAND[0]), DEMO_HAND[1])
        now = datetime.now(UTC)
        for name, line in DEMO_CHAT:
            post_message(session, chat_room(class_session_id), _account(session, name), line, now)
    manager.close()  # the launcher lets go before its workers fork: the robots run on in the farm
    return [f"a class session of the demo course with {len(DEMO_PUPILS) + 1} students on robots of their own, "
            "a raised hand and the class chat (the tutor's class wall)"]


def _account(session: Session, username: str) -> User:
    user = find_user(session, username)
    assert user is not None, username  # created above, in this seed
    return user


def _restart_robots(sessions: sessionmaker[Session], manager: PracticeManager, class_session_id: int) -> list[str]:
    """Starts again the robots of the open demo class that the farm no longer runs (an earlier lab's)."""
    with sessions() as session, session.begin():
        running = set(session.scalars(select(PersonalRobotRecord.owner_id).where(
            PersonalRobotRecord.class_session_id == class_session_id)))
        stopped = [user_id for user_id in session.scalars(select(ClassSeat.user_id).where(
            ClassSeat.session_id == class_session_id)) if user_id not in running]
        if stopped:
            session.execute(update(ClassSeat).where(ClassSeat.session_id == class_session_id,
                                                    ClassSeat.user_id.in_(stopped)).values(state="starting",
                                                                                           message=""))
    if not stopped:
        return []
    class_sessions.start_robots(sessions, manager, class_session_id)  # a running robot's start finds it running
    manager.close()
    return [f"the demo class's robots started again ({len(stopped)})"]
