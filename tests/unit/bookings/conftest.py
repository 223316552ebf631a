"""A migrated database with a course, its tutor and two students, for the booking rules."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import pytest
from sqlalchemy.orm import Session, sessionmaker

from middleware.db import make_engine
from middleware.models import Course, CourseMembership, User
from tests.conftest import migrate_to_head


@dataclass
class People:
    """Ids of the accounts and courses the tests use."""

    student: int
    other_student: int
    tutor: int
    other_tutor: int
    admin: int
    course: int
    other_course: int


def seed(session: Session) -> People:
    """Two courses (120 and 60 min a week), a tutor for each, two students in the first, an admin."""
    users = {name: User(username=name, role=role, password_hash="x") for name, role in [
        ("stud", "student"), ("stud2", "student"), ("tut", "tutor"), ("tut2", "tutor"), ("adm", "admin")]}
    session.add_all(users.values())
    course, other = Course(code="ROB1", title="Robotics 1", booking_allowance_min=120), \
        Course(code="ROB2", title="Robotics 2", booking_allowance_min=60)
    session.add_all([course, other])
    session.flush()
    session.add_all([
        CourseMembership(course_id=course.id, user_id=users["stud"].id, role="student"),
        CourseMembership(course_id=course.id, user_id=users["stud2"].id, role="student"),
        CourseMembership(course_id=course.id, user_id=users["tut"].id, role="tutor"),
        CourseMembership(course_id=other.id, user_id=users["tut2"].id, role="tutor"),
    ])
    session.commit()
    return People(users["stud"].id, users["stud2"].id, users["tut"].id, users["tut2"].id, users["adm"].id,
                  course.id, other.id)


@pytest.fixture
def factory(database_url: str) -> Iterator[sessionmaker[Session]]:
    """Sessions on a migrated database (SQLite and PostgreSQL)."""
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    yield sessionmaker(bind=engine, expire_on_commit=False)
    engine.dispose()


@pytest.fixture
def people(factory: sessionmaker[Session]) -> People:
    """The seeded accounts."""
    with factory() as session:
        return seed(session)
