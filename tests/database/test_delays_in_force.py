"""Which video delays are in force, read by the delay book on SQLite and PostgreSQL: a trial's only on its robot."""

from __future__ import annotations

from sqlalchemy import Engine
from sqlalchemy.orm import Session

from middleware.experiment import services
from middleware.experiment.delay import delay_in_force_s, read_all_delays_s
from middleware.models import Course, CourseMembership, User
from tests.conftest import ready_for_trials


def _accounts(session: Session) -> tuple[User, User]:
    student = User(username="ann", role="student", password_hash="x")
    tutor = User(username="tim", role="tutor", password_hash="x")
    course = Course(code="EXP", title="Experiment")
    session.add_all([student, tutor, course])
    session.flush()
    session.add_all([CourseMembership(course_id=course.id, user_id=student.id, role="student"),
                     CourseMembership(course_id=course.id, user_id=tutor.id, role="tutor")])  # tim teaches ann
    session.flush()
    ready_for_trials(session, "ann")
    return student, tutor


def _in_force(session: Session, user: User, robot_name: str) -> float:
    return delay_in_force_s(read_all_delays_s(session), user.id, robot_name)


def test_an_open_trial_delays_its_robot_only_and_giving_it_up_ends_the_delay(engine: Engine) -> None:
    with Session(engine) as session:
        student, _ = _accounts(session)
        trial = services.assign_trial(session, student, "course-b", "course-B")
        session.commit()
        assert _in_force(session, student, "course-b") == trial.delay_s > 0
        assert _in_force(session, student, "lab-1") == 0.0
        services.abandon_trial(session, student, trial.id)
        session.commit()
        assert _in_force(session, student, "course-b") == 0.0
        nxt = services.assign_trial(session, student, "course-b", "course-B")
        session.commit()
        assert nxt.id != trial.id and _in_force(session, student, "course-b") == nxt.delay_s
        services.finish_trial(session, student, nxt.id, services.RunResult(12.5, 0))
        session.commit()
        assert _in_force(session, student, "course-b") == 0.0


def test_a_tutor_s_delay_is_on_every_robot_outlives_trials_and_yields_to_a_trial_on_its_robot(
    engine: Engine,
) -> None:
    with Session(engine) as session:
        student, tutor = _accounts(session)
        services.set_video_delay(session, tutor, student.id, 5)
        trial = services.assign_trial(session, student, "course-b", "course-B")
        session.commit()
        assert _in_force(session, student, "lab-1") == 5.0
        assert _in_force(session, student, "course-b") == trial.delay_s
        services.abandon_trial(session, student, trial.id)
        session.commit()
        assert _in_force(session, student, "course-b") == _in_force(session, student, "lab-1") == 5.0


def test_the_upgrade_removes_delays_that_trials_copied_and_keeps_tutors(database_url: str) -> None:
    from alembic import command
    from sqlalchemy import text

    from middleware.db import alembic_config, make_engine, upgrade_to_head

    command.upgrade(alembic_config(database_url), "0009")
    engine = make_engine(database_url)
    with engine.begin() as connection:  # plain SQL: the models may have outgrown revision 0009
        for name, role in (("ann", "student"), ("tim", "tutor")):
            connection.execute(text("INSERT INTO users (username, role, password_hash, is_active, created_at) "
                                    "VALUES (:name, :role, 'x', TRUE, CURRENT_TIMESTAMP)"),
                               {"name": name, "role": role})
        ids = dict(connection.execute(text("SELECT username, id FROM users")).all())
        connection.execute(text("INSERT INTO video_delays (user_id, delay_s, set_by_id, updated_at) VALUES "
                                "(:ann, 3, NULL, CURRENT_TIMESTAMP), (:tim, 2, :tim, CURRENT_TIMESTAMP)"), ids)
    upgrade_to_head(database_url)
    with Session(engine) as session:
        assert read_all_delays_s(session) == {(ids["tim"], None): 2.0}
    engine.dispose()
