"""The obstacle-zone rule's question (middleware/assessment/hidden_obstacles.py), on SQLite and PostgreSQL: a student's
obstacle-zone attempt in progress hides the obstacles from them until it is submitted or its deadline passes;
another task kind, another student or a tutor is not concerned. And the filters keep the walls only."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import update
from sqlalchemy.orm import Session

from middleware.assessment.hidden_obstacles import (
    HIDDEN_VERSION_SUFFIX,
    hides_obstacles,
    info_without_obstacles,
    scene_without_obstacles,
)
from middleware.db import make_engine
from middleware.models import Course, User
from middleware.models.assessment import Attempt, Exam
from tests.conftest import migrate_to_head

NOW = datetime(2026, 11, 26, 12, 0, tzinfo=UTC)


@pytest.fixture
def session(database_url: str) -> Iterator[Session]:
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    with Session(engine) as opened:
        yield opened
    engine.dispose()


def person(session: Session, name: str, role: str = "student") -> int:
    user = User(username=name, role=role, password_hash="x")
    session.add(user)
    session.flush()
    return user.id


def attempt_at(session: Session, user_id: int, task_kind: str, deadline: datetime | None) -> int:
    """An experimental exam whose task is of task_kind, and user_id's attempt at it in progress; the attempt's id."""
    course = Course(code=f"C{user_id}{task_kind[:3]}", title="C")
    session.add(course)
    session.flush()
    exam = Exam(course_id=course.id, title=task_kind, kind="experimental", duration_s=900, max_attempts=1,
                robot_name="lab-1", task={"kind": task_kind, "obstacles": [], "bounds": [0, 0, 1, 1]})
    session.add(exam)
    session.flush()
    attempt = Attempt(exam_id=exam.id, user_id=user_id, status="in_progress", open_key=f"{exam.id}:{user_id}",
                      started_at=NOW - timedelta(minutes=1), deadline_at=deadline, answers={})
    session.add(attempt)
    session.flush()
    return attempt.id


def test_only_an_obstacle_zone_attempt_in_progress_hides_the_obstacles_from_its_student(session: Session) -> None:
    ann, bob, tutor = person(session, "ann"), person(session, "bob"), person(session, "tom", "tutor")
    attempt_at(session, bob, "reach_point", NOW + timedelta(minutes=10))
    zone = attempt_at(session, ann, "obstacle_zone", NOW + timedelta(minutes=10))
    assert hides_obstacles(session, ann, NOW)
    assert not hides_obstacles(session, bob, NOW)  # another task kind
    assert not hides_obstacles(session, tutor, NOW)
    assert not hides_obstacles(session, ann, NOW + timedelta(minutes=11))  # the deadline passed, not settled yet
    session.execute(update(Attempt).where(Attempt.id == zone).values(status="submitted", open_key=None))
    assert not hides_obstacles(session, ann, NOW)


def test_an_untimed_zone_attempt_hides_the_obstacles_until_it_is_submitted(session: Session) -> None:
    ann = person(session, "ann")
    attempt_at(session, ann, "obstacle_zone", None)
    assert hides_obstacles(session, ann, NOW + timedelta(days=1))


def test_the_filters_keep_the_walls_and_say_why() -> None:
    scene = {"version": "v7", "blocks": [{"name": "wall_east"}, {"name": "crate"}],
             "cylinders": [{"name": "pillar"}], "marks": [{"kind": "grid"}]}
    hidden = scene_without_obstacles(scene)
    assert hidden["blocks"] == [{"name": "wall_east"}] and hidden["cylinders"] == []
    assert hidden["version"] == "v7" + HIDDEN_VERSION_SUFFIX and hidden["marks"] == scene["marks"]
    assert "obstacle-zone test" in hidden["obstacles_hidden"]
    info = info_without_obstacles({"robot_name": "lab-1", "scene_boxes": [{"name": "wall_north"}, {"name": "bench"}]})
    assert info["scene_boxes"] == [{"name": "wall_north"}] and info["robot_name"] == "lab-1"
