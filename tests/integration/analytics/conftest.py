"""A lab with a seeded week of history (sessions, queue waits, outages, maintenance, lessons, tours, tests,
exercises), once on SQLite and once on PostgreSQL, served, with clients logged in as each role. Every figure the
tests expect is worked out by hand in the comments of history()."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from datetime import UTC, datetime

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, add_test_account, make_test_app

ROLES = {"ta": "tutor", "tb": "tutor", "s1": "student", "s2": "student", "s3": "student", "ad": "admin"}
# The window the tests ask for: Monday 2 to Sunday 8 March 2026 in a zone one hour east of UTC, so from
# 2026-03-01 23:00 UTC to 2026-03-08 23:00 UTC.
WINDOW = {"from": "2026-03-02", "to": "2026-03-08", "utc_offset_min": "60"}


def at(day: int, hour: int, minute: int = 0) -> datetime:
    """A moment of March 2026, UTC."""
    return datetime(2026, 3, day, hour, minute, tzinfo=UTC)


def history(app) -> dict[str, int]:
    """The seeded history; name -> id."""
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, Robot
    from middleware.models.analytics import LearningEvent, QueueWait, RobotOutage
    from middleware.models.assessment import Attempt, Exam
    from middleware.models.exercises import Exercise, ExerciseAssignment, ExerciseCode, ExerciseRun
    from middleware.models.recordings import Recording
    from middleware.models.robots import RobotMaintenance
    from middleware.models.teaching import Lesson, Tour

    ids: dict[str, int] = {}
    with session_factory(app)() as session:
        users = {name: add_test_account(session, name, role) for name, role in ROLES.items()}
        ids.update({name: user.id for name, user in users.items()})
        course_a, course_b = Course(code="ANA", title="Analytics A"), Course(code="ANB", title="Analytics B")
        session.add_all([course_a, course_b])
        session.flush()
        ids["A"], ids["B"] = course_a.id, course_b.id
        for name, course, role in [("ta", course_a, "tutor"), ("s1", course_a, "student"),
                                   ("s2", course_a, "student"), ("tb", course_b, "tutor"), ("s3", course_b, "student")]:
            session.add(CourseMembership(course_id=course.id, user_id=users[name].id, role=role))
        if session.query(Robot).filter_by(name="lab-1").first() is None:
            session.add(Robot(name="lab-1", title="Lab 1", address="127.0.0.1:9", kind="lab"))

        def recording(user: str, robot: str, start: datetime, end: datetime, reason: str, commands: int = 0,
                      skills: int = 0, plans: int = 0) -> int:
            row = Recording(user_id=users[user].id, robot_name=robot, kind="turn", explicit=False, started_at=start,
                            ended_at=end, end_reason=reason, status="ready", command_count=commands,
                            skill_count=skills, plan_count=plans)
            session.add(row)
            session.flush()
            return row.id

        # s1: Mon 09:30-10:15 UTC (local 10:30-11:15: Mon 10h 30 min, 11h 15 min), 45 min.
        ids["r1"] = recording("s1", "lab-1", at(2, 9, 30), at(2, 10, 15), "turn_ended", 12, 2, 1)
        # s1: Wed 22:50 - Thu 00:20 UTC (local Wed 23:50 - Thu 01:20: Wed 23h 10, Thu 0h 60, Thu 1h 20), 90 min.
        ids["r2"] = recording("s1", "lab-1", at(4, 22, 50), at(5, 0, 20), "handed_over", 30)
        # s2: Sun 22:30-23:30 UTC; the window ends at 23:00 UTC: 30 min counted (local Sun 23h).
        ids["r3"] = recording("s2", "practice-s2", at(8, 22, 30), at(8, 23, 30), "robot_stopped", 5)
        # s2: before the window (Sun 1 March 22:00-22:30 UTC, local 23:00-23:30 on the 1st): not counted.
        ids["r4"] = recording("s2", "lab-1", at(1, 22, 0), at(1, 22, 30), "turn_ended", 1)
        # s3 of course B: Tue 12:00-13:00 UTC, an hour on lab-1 (the admin's figures only).
        ids["r5"] = recording("s3", "lab-1", at(3, 12), at(3, 13), "turn_ended", 7)
        # Queue waits: course A's are 0, 10, 45, 200 and 700 s; s3's 5000 s; one of s1's after the window.
        for user, seconds, granted in [("s1", 0.0, at(2, 9, 30)), ("s1", 45.0, at(4, 22, 50)), ("s1", 200.0, at(6, 8)),
                                       ("s2", 10.0, at(3, 9)), ("s2", 700.0, at(7, 15)), ("s3", 5000.0, at(3, 12)),
                                       ("s1", 99.0, at(10, 12))]:
            session.add(QueueWait(robot_name="lab-1", user_id=users[user].id, granted_at=granted, wait_s=seconds,
                                  waited_from=granted.replace(second=0) if seconds == 0 else granted))
        # Outages: lab-1 Tue 10:00-10:30 (30 min) and Sun 1 22:00 - Mon 2 00:00 UTC (60 min within the window);
        # ghost2 from Sun 8 22:00 UTC, still open (60 min within the window).
        session.add_all([RobotOutage(robot_name="lab-1", started_at=at(3, 10), ended_at=at(3, 10, 30)),
                         RobotOutage(robot_name="lab-1", started_at=at(1, 22), ended_at=at(2, 0)),
                         RobotOutage(robot_name="ghost2", started_at=at(8, 22), ended_at=None),
                         RobotMaintenance(robot_name="lab-1", actor_id=users["ta"].id, action="restart",
                                          outcome="restarted", created_at=at(3, 10, 31)),
                         RobotMaintenance(robot_name="lab-1", actor_id=users["ta"].id, action="dock",
                                          outcome="docked", created_at=at(5, 9))])
        lesson = Lesson(slug="an-lesson", title="Odometry lesson", video_name="v.mp4", cues_vtt="WEBVTT\n")
        tour = Tour(slug="an-tour", title="Sonar tour", steps_json="[]")
        session.add_all([lesson, tour])
        session.flush()
        ids["lesson"], ids["tour"] = lesson.id, tour.id
        session.add_all([LearningEvent(user_id=users["s1"].id, kind="lesson_watched", object_id=lesson.id,
                                       at=at(3, 8)),
                         LearningEvent(user_id=users["s2"].id, kind="tour_followed", object_id=tour.id, at=at(4, 8))])
        exam_a = Exam(course_id=course_a.id, title="Test A", kind="quiz", question_ids=[])
        exam_b = Exam(course_id=course_b.id, title="Test B", kind="quiz", question_ids=[])
        session.add_all([exam_a, exam_b])
        session.flush()
        session.add_all([
            Attempt(exam_id=exam_a.id, user_id=users["s1"].id, status="submitted", started_at=at(5, 10),
                    submitted_at=at(5, 10, 20), submitted_by="student", answers={}, auto_score=3.0, max_score=4.0),
            Attempt(exam_id=exam_b.id, user_id=users["s3"].id, status="submitted", started_at=at(5, 10),
                    submitted_at=at(5, 10, 20), submitted_by="student", answers={}, auto_score=1.0, max_score=4.0)])
        exercise = Exercise(slug="an-ex", title="Bump and go", statement="s", template="t", rubric_json="{}",
                            start_json="[0, 0, 0]")
        session.add(exercise)
        session.flush()
        session.add(ExerciseAssignment(course_id=course_a.id, exercise_id=exercise.id, deadline_at=at(20, 0)))
        code = ExerciseCode(exercise_id=exercise.id, user_id=users["s2"].id, code="pass")
        session.add(code)
        session.flush()
        session.add(ExerciseRun(exercise_id=exercise.id, user_id=users["s2"].id, code_id=code.id,
                                robot_name="practice-s2", mode="submission", start_json="[0, 0, 0]",
                                started_at=at(6, 9), ended_at=at(6, 9, 1), status="graded", fraction=0.8))
        session.commit()
    return ids


@pytest.fixture(scope="module")
def lab(module_database_url: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LiveServer, dict]]:
    """The app (no robot answers: none is needed) with the history, served."""
    from tests.conftest import _let_go

    app = make_test_app(module_database_url, "lab-1=127.0.0.1:9", tmp_path_factory.mktemp("analytics"))
    ids = history(app)
    server = LiveServer(app)
    try:
        yield server, ids
    finally:
        server.stop()
        _let_go(app)


@pytest.fixture(scope="module")
def client_of(lab) -> Callable[[str], LabClient]:
    """A client logged in as the named account (made once per module)."""
    server, _ids = lab
    made: dict[str, LabClient] = {}

    def make(username: str) -> LabClient:
        if username not in made:
            client = LabClient(server.url)
            assert client.login(username, STUDENT_PASSWORD) == 302
            made[username] = client
        return made[username]

    return make
