"""The thesis' protocol on SQLite and PostgreSQL: a class starting its first trials at the same moment gets the
design's orders within one student of each other; a student runs their order through, a given-up trial again, and
begins nothing before answering the questions and finishing the learning period."""

from __future__ import annotations

import threading
from collections import Counter
from datetime import timedelta

import pytest
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from middleware.errors import Refused
from middleware.experiment import protocol, services
from middleware.models import Course, CourseMembership, User
from middleware.models.accounts import utc_now
from middleware.models.experiment import Participant

CLASS_SIZE = 13


def _class(engine: Engine) -> tuple[int, list[int], int]:
    with Session(engine) as session:
        course = Course(code="EXP", title="Experiment")
        tutor = User(username="tim", role="tutor", password_hash="x")
        students = [User(username=f"s{i:02d}", role="student", password_hash="x") for i in range(CLASS_SIZE)]
        session.add_all([course, tutor, *students])
        session.flush()
        session.add(CourseMembership(course_id=course.id, user_id=tutor.id, role="tutor"))
        session.add_all(CourseMembership(course_id=course.id, user_id=s.id, role="student") for s in students)
        session.flush()
        for student in students:
            session.add(Participant(user_id=student.id, consent=False, answered_at=utc_now(),
                                    learning_started_at=utc_now() - timedelta(hours=1)))
        session.commit()
        return course.id, [s.id for s in students], tutor.id


def test_a_class_beginning_at_once_gets_the_designs_orders_within_one_of_each_other(engine: Engine) -> None:
    course_id, students, _ = _class(engine)
    gate = threading.Barrier(CLASS_SIZE)
    failures: list[BaseException] = []

    def begin(user_id: int) -> None:
        try:
            with Session(engine) as session:
                student = session.get(User, user_id)
                gate.wait(10)
                services.assign_trial(session, student, "course-a", "course-A")
                session.commit()
        except BaseException as error:  # noqa: BLE001 - reported below
            failures.append(error)

    threads = [threading.Thread(target=begin, args=(user_id,)) for user_id in students]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert failures == []
    with Session(engine) as session:
        used = protocol.participants_summary(session, set(students))["orders_in_use"]
        rows = [session.get(Participant, user_id) for user_id in students]
    assert all(row is not None and row.order_course_id == course_id for row in rows)
    assert sum(used) == CLASS_SIZE and max(used) - min(used) <= 1, used


def test_a_student_runs_every_condition_of_their_order_and_a_given_up_one_again(engine: Engine) -> None:
    _, students, _ = _class(engine)
    with Session(engine) as session:
        student = session.get(User, students[0])
        order = protocol.order_of(session, student, None)
        run: list[tuple[float, bool]] = []
        for step in range(len(order) + 1):
            trial = services.assign_trial(session, student, "course-a", "course-A")
            if step == 1:
                services.abandon_trial(session, student, trial.id)
                again = services.assign_trial(session, student, "course-a", "course-A")
                assert (again.delay_s, again.feedback) == (trial.delay_s, trial.feedback), "given up: run again"
                trial = again
            run.append((trial.delay_s, trial.feedback))
            services.finish_trial(session, student, trial.id, services.RunResult(30.0 + step, 0))
            session.commit()
    assert run[:len(order)] == order and sorted(order) == sorted(protocol.CONDITIONS_PER_COURSE)
    assert run[-1] == order[0], "the order starts over once it is through"
    assert Counter(run).most_common(1)[0][1] == 2


def test_nothing_begins_before_the_questions_and_the_learning_period(engine: Engine) -> None:
    course_id, students, tutor_id = _class(engine)
    with Session(engine) as session:
        student = session.get(User, students[0])
        session.delete(session.get(Participant, student.id))
        session.commit()
        with pytest.raises(Refused) as refused:
            services.assign_trial(session, student, "course-a", "course-A")
        assert (refused.value.code, refused.value.field) == ("details_missing", "consent")
        protocol.answer_details(session, student, {"consent": True, "age": 23, "location": "remote"})
        with pytest.raises(Refused) as refused:
            services.assign_trial(session, student, "course-a", "course-A")
        assert (refused.value.code, refused.value.field) == ("learning_not_started", "learning")
        protocol.start_learning(session, student)
        with pytest.raises(Refused) as refused:
            services.assign_trial(session, student, "course-a", "course-A")
        assert refused.value.code == "learning_period" and "ends in 300 s" in refused.value.message
        protocol.set_protocol(session, session.get(User, tutor_id), course_id, {"learning_s": 0})
        assert services.assign_trial(session, student, "course-a", "course-A").user_id == student.id
        session.commit()
