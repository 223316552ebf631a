"""A graded run keeps a shared robot past the turn length while others wait, and gives it back when it ends or
when the course's longest hold has passed; it never takes the robot from another student's turn (the rule as
create_app composes it, on SQLite and PostgreSQL)."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import timedelta

import pytest
from sqlalchemy import Engine, update
from sqlalchemy.orm import Session

from middleware.access.graded_runs import with_graded_run_priority
from middleware.access.round_robin import AccessPolicy
from middleware.bookings.services import priority_user_id as booking_priority
from middleware.db import make_engine
from middleware.models import Course, CourseMembership, User
from middleware.models.assessment import Attempt, Exam
from middleware.models.experiment import TRIAL_OPEN, Trial
from middleware.teaching.tours import with_guided_priority
from tests.conftest import migrate_to_head
from tests.database.test_round_robin import ROBOT, T0, TURN_S, Lab

HOLD_MIN = 10


class RunLab(Lab):
    """The round-robin Lab with the composed priority and two students of a course that holds runs 10 minutes."""

    def __init__(self, engine: Engine) -> None:
        super().__init__(engine)
        self.policy = AccessPolicy(grace_s=36000.0, turn_length_s=lambda _s, _u: TURN_S,
                                   priority_user_id=with_graded_run_priority(with_guided_priority(booking_priority)))
        with Session(engine) as session, session.begin():
            people = [User(username=name, role="student", password_hash="x") for name in ("ann", "bob")]
            course = Course(code="R1", title="R", graded_run_hold_min=HOLD_MIN)
            session.add_all([*people, course])
            session.flush()
            session.add_all(CourseMembership(course_id=course.id, user_id=p.id, role="student") for p in people)
            exam = Exam(course_id=course.id, title="Reach the tile", kind="experimental", duration_s=3600,
                        max_attempts=1, robot_name=ROBOT)
            session.add(exam)
            session.flush()
            self.ann, self.bob, self.exam = people[0].id, people[1].id, exam.id

    def start_attempt(self, user_id: int, at_s: float) -> int:
        started = T0 + timedelta(seconds=at_s)
        with Session(self.engine) as session, session.begin():
            attempt = Attempt(exam_id=self.exam, user_id=user_id, status="in_progress",
                              open_key=f"{self.exam}:{user_id}", started_at=started,
                              deadline_at=started + timedelta(hours=1), answers={})
            session.add(attempt)
            session.flush()
            return attempt.id

    def submit(self, attempt_id: int) -> None:
        with Session(self.engine) as session, session.begin():
            session.execute(update(Attempt).where(Attempt.id == attempt_id)
                            .values(status="submitted", open_key=None, submitted_at=T0))

    def start_trial(self, user_id: int, at_s: float) -> int:
        with Session(self.engine) as session, session.begin():
            trial = Trial(user_id=user_id, robot_name=ROBOT, course="course-A", delay_s=1.0, feedback=True,
                          status=TRIAL_OPEN, created_at=T0 + timedelta(seconds=at_s))
            session.add(trial)
            session.flush()
            return trial.id

    def finish_trial(self, trial_id: int) -> None:
        with Session(self.engine) as session, session.begin():
            session.execute(update(Trial).where(Trial.id == trial_id).values(status="completed"))


@pytest.fixture
def lab(database_url: str) -> Iterator[RunLab]:
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    yield RunLab(engine)
    engine.dispose()


def test_an_attempt_keeps_the_robot_past_the_turn_and_gives_it_back_at_the_end(lab: RunLab) -> None:
    lab.join(lab.ann, at_s=0)
    attempt = lab.start_attempt(lab.ann, at_s=5)
    lab.join(lab.bob, at_s=10)
    for at_s in (10.5, TURN_S + 20, 3 * TURN_S):
        state = lab.tick(at_s=at_s)
        assert state.controller_id == lab.ann and state.turn_ends_at is None, at_s  # no countdown: bob waits
        assert state.waiting_ids == (lab.bob,)
    lab.submit(attempt)
    ended = lab.tick(at_s=3 * TURN_S + 1)
    assert ended.controller_id == lab.ann and ended.turn_ends_at is not None  # an ordinary turn from now
    assert lab.tick(at_s=4 * TURN_S + 2).controller_id == lab.bob


def test_a_trial_keeps_the_robot_until_it_is_finished(lab: RunLab) -> None:
    lab.join(lab.bob, at_s=0)
    trial = lab.start_trial(lab.bob, at_s=1)
    lab.join(lab.ann, at_s=2)
    assert lab.tick(at_s=2 * TURN_S).controller_id == lab.bob
    lab.finish_trial(trial)
    assert lab.tick(at_s=2 * TURN_S + 1).turn_ends_at is not None
    assert lab.tick(at_s=3 * TURN_S + 2).controller_id == lab.ann


def test_the_hold_ends_after_the_courses_longest_hold(lab: RunLab) -> None:
    lab.join(lab.ann, at_s=0)
    lab.start_trial(lab.ann, at_s=0)
    lab.join(lab.bob, at_s=1)
    assert lab.tick(at_s=HOLD_MIN * 60 - 1).turn_ends_at is None
    over = lab.tick(at_s=HOLD_MIN * 60 + 1)
    assert over.controller_id == lab.ann and over.turn_ends_at is not None  # a forgotten trial lets go
    assert lab.tick(at_s=HOLD_MIN * 60 + TURN_S + 2).controller_id == lab.bob


def test_a_run_waits_for_its_turn_and_never_takes_the_robot_from_another_student(lab: RunLab) -> None:
    lab.join(lab.bob, at_s=0)
    lab.join(lab.ann, at_s=1)
    lab.start_attempt(lab.ann, at_s=2)  # ann starts her test while bob drives
    state = lab.tick(at_s=3)
    assert state.controller_id == lab.bob and state.turn_ends_at is not None
    assert lab.tick(at_s=TURN_S + 5).controller_id == lab.ann  # her turn came in line ...
    assert lab.tick(at_s=3 * TURN_S).controller_id == lab.ann  # ... and her run keeps it past the turn
