"""The elected recorder asks every second which sessions go on and what each is for: an attempt in progress on that
robot, else a trial assigned on it, else the session's own kind. It reads that in a fixed number of queries, however
many robots run (it read two rows per robot per second)."""

from __future__ import annotations

from datetime import timedelta

from sqlalchemy import event
from sqlalchemy.orm import Session

from tests.conftest import add_test_account


def test_each_session_gets_the_kind_of_what_its_person_does_on_that_robot_in_a_fixed_number_of_queries(
        engine) -> None:
    from middleware.models.access import RobotControl
    from middleware.models.accounts import utc_now
    from middleware.models.assessment import Attempt, Exam
    from middleware.models.courses import Course
    from middleware.models.experiment import Trial
    from middleware.models.farm import PersonalRobotRecord
    from middleware.recordings.services import wanted_sessions

    now = utc_now()
    with Session(engine) as session:
        people = [add_test_account(session, f"kinds{n}", "student") for n in range(5)]
        course = Course(code="KINDS", title="Kinds")
        session.add(course)
        session.flush()
        exam = Exam(course_id=course.id, title="Drive", kind="experimental", robot_name="lab-1")
        session.add(exam)
        session.flush()
        session.add_all([
            RobotControl(robot_name="lab-1", controller_id=people[0].id, turn_started_at=now),
            RobotControl(robot_name="lab-2", controller_id=people[1].id, turn_started_at=now),
            RobotControl(robot_name="lab-3", controller_id=people[2].id, turn_started_at=now),
            Attempt(exam_id=exam.id, user_id=people[0].id, started_at=now, robot_name="lab-1"),
            Attempt(exam_id=exam.id, user_id=people[1].id, started_at=now, robot_name="lab-9"),  # another robot
            Trial(user_id=people[1].id, robot_name="lab-2", course="course-A", delay_s=0, feedback=False),
            Trial(user_id=people[2].id, robot_name="lab-3", course="course-A", delay_s=0, feedback=False,
                  status="completed"),
            PersonalRobotRecord(name="practice-kinds3", owner_id=people[3].id, owner_name="kinds3", scene="lab",
                                token="t3", address="127.0.0.1:1", backend="local",
                                started_at=now - timedelta(minutes=1)),
            PersonalRobotRecord(name="practice-kinds4", owner_id=people[4].id, owner_name="kinds4", scene="lab",
                                token="t4", address="127.0.0.1:2", backend="local", started_at=now),
            Attempt(exam_id=exam.id, user_id=people[4].id, started_at=now, robot_name="practice-kinds4",
                    status="in_progress", open_key="exam:4"),
        ])
        session.commit()
        ids = [person.id for person in people]

        statements: list[str] = []
        event.listen(engine, "before_cursor_execute", lambda *args: statements.append(args[2]))
        wanted = wanted_sessions(session)
    kinds = {robot: (found.kind, found.user_id) for robot, found in wanted.items()}
    assert kinds == {
        "lab-1": ("test_attempt", ids[0]),
        "lab-2": ("experiment_trial", ids[1]),
        "lab-3": ("turn", ids[2]),  # its trial is over
        "practice-kinds3": ("practice", ids[3]),
        "practice-kinds4": ("test_attempt", ids[4]),
    }
    assert len(statements) == 4, statements  # attempts, trials, the controls, the practice robots
