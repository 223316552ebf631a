"""Graded work on the student's own robot in a class session: an experimental test's attempt runs and is recorded
on it (no turn on the shared robot needed), and the delay experiment's trials run on it when the class runs a
course scene; outside a class, or with another scene, the shared robot's rules apply as before."""

from __future__ import annotations

import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from tests.conftest import (
    STUDENT_PASSWORD,
    LabClient,
    LiveServer,
    _let_go,
    add_test_account,
    make_course,
    make_test_app,
    ready_for_trials,
)
from tests.integration.teaching.test_class_sessions import _wait_until_ready
from tests.integration.teaching.test_practice_console_and_uploads import _api


@pytest.fixture
def small_class(tmp_path: Path, skill_server_address: str) -> Iterator[tuple[LiveServer, int, int]]:
    """tutor1 teaching ann and bob, an experimental test on lab-1 (scene lab) open now; (server, course, exam)."""
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager

    app = make_test_app(f"sqlite:///{tmp_path / 'class.sqlite3'}", f"lab-1={skill_server_address}", tmp_path)
    with session_factory(app)() as session:
        for name, role in (("tutor1", "tutor"), ("ann", "student"), ("bob", "student")):
            add_test_account(session, name, role)
        session.commit()
    course_id = make_course(app, "ROB101", {"tutor1": "tutor", "ann": "student", "bob": "student"})
    ready_for_trials(app, "ann")
    now = datetime.now(UTC)
    with session_factory(app)() as session:
        exam = bank.create_exam(session, find_user(session, "tutor1"), course_id, parse_exam({
            "title": "Drive to the point", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "task_kind": "reach_point",
            "x_m": 0.0, "y_m": 0.0, "rubric": "0.1:1, 0.5:0.5, 2:0.25", "task_points": 10, "robot_name": "lab-1"}))
        session.commit()
        exam_id = exam.id
    server = LiveServer(app)
    try:
        yield server, course_id, exam_id
    finally:
        practice_manager(app).shutdown()
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper


def _login(server: LiveServer, name: str) -> LabClient:
    client = LabClient(server.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def test_an_experimental_attempt_in_class_runs_and_is_recorded_on_the_students_own_robot(small_class) -> None:
    from middleware.db import session_factory
    from middleware.models.assessment import Attempt

    server, course_id, exam_id = small_class
    tutor, ann, bob = (_login(server, name) for name in ("tutor1", "ann", "bob"))
    status, error = _api(ann, "POST", f"/api/exams/{exam_id}/attempts")
    assert (status, error["error"]["code"]) == (409, "no_robot"), "outside a class: the shared robot's rule"

    status, opened = _api(tutor, "POST", f"/api/courses/{course_id}/class-session", {"scene": "lab"})
    assert status == 201 and opened["scene"] == "lab", opened
    assert _wait_until_ready(tutor, course_id)["counts"]["ready"] == 2
    status, started = _api(ann, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201 and started["attempt"]["exam"]["robot_name"] == "practice-ann", started
    status, _, page = ann.request("GET", f"/assessment/attempts/{started['attempt']['id']}")
    assert status == 200 and 'href="/lab/practice-ann"' in page and "Open practice-ann in a new tab" in page
    for _ in range(8):  # drive her own robot for 2 s, as the console's joystick would
        status, ran = _api(ann, "POST", "/api/practice/commands", {"command": {"drive": {"linear_mps": 0.2}}})
        assert status == 202, ran
        time.sleep(0.25)
    time.sleep(1.0)
    status, submitted = _api(ann, "POST", f"/api/attempts/{started['attempt']['id']}/submit")
    assert status == 200, submitted
    with session_factory(server.app)() as session:
        attempt = session.get(Attempt, started["attempt"]["id"])
        assert attempt.robot_name == "practice-ann" and attempt.trace and len(attempt.trace) >= 3
        assert attempt.trace[-1][1] != pytest.approx(attempt.trace[0][1], abs=0.02), "the own robot's run moved"
    status, bob_started = _api(bob, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201 and bob_started["attempt"]["exam"]["robot_name"] == "practice-bob"


def test_a_class_on_a_course_scene_runs_the_experiments_trials_on_each_students_robot(small_class) -> None:
    server, course_id, exam_id = small_class
    tutor, ann = _login(server, "tutor1"), _login(server, "ann")
    status, error = _api(tutor, "POST", f"/api/courses/{course_id}/class-session", {"scene": "mars"})
    assert (status, error["error"]["field"]) == (400, "scene")
    status, opened = _api(tutor, "POST", f"/api/courses/{course_id}/class-session", {"scene": "course-A"})
    assert status == 201 and opened["scene"] == "course-A"
    _wait_until_ready(tutor, course_id)
    status, state = _api(ann, "GET", "/api/experiment/state")
    assert state["robots"][0] == {"name": "practice-ann", "scene": "course-A", "own": True}, state
    status, trial = _api(ann, "POST", "/api/experiment/trials", {"robot_name": "practice-ann"})
    assert status == 201 and trial["trial"]["robot_name"] == "practice-ann" and trial["trial"]["course"] == "course-A"
    status, refused = _api(ann, "POST", f"/api/experiment/trials/{trial['trial']['id']}/finish")
    assert (status, refused["error"]["code"]) == (409, "run_not_finished"), "her own robot: she is its controller"
    bob = _login(server, "bob")
    status, error = _api(bob, "POST", "/api/experiment/trials", {"robot_name": "practice-ann"})
    assert (status, error["error"]["field"]) == (400, "robot_name"), "another student's robot is not offered"
    status, error = _api(ann, "POST", f"/api/exams/{exam_id}/attempts")
    assert (status, error["error"]["code"]) == (409, "no_robot"), "her robot runs course-A, the test's robot lab"


def test_a_class_booking_opens_its_session_before_the_slot_and_ends_it_with_the_slot(small_class) -> None:
    from sqlalchemy import select, update

    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.models import Booking
    from middleware.models.farm import ClassSession
    from middleware.teaching.class_bookings import sync_with_bookings
    from middleware.teaching.practice_robots import practice_manager

    server, course_id, _exam = small_class
    sessions, manager = session_factory(server.app), practice_manager(server.app)
    now = datetime.now(UTC)
    with sessions() as session:
        tutor = find_user(session, "tutor1")
        booking = Booking(robot_name="lab-1", user_id=tutor.id, course_id=course_id, kind="class",
                          starts_at=now + timedelta(minutes=3), ends_at=now + timedelta(minutes=63))
        later = Booking(robot_name="lab-1", user_id=tutor.id, course_id=course_id, kind="class",
                        starts_at=now + timedelta(hours=3), ends_at=now + timedelta(hours=4))
        session.add_all([booking, later])
        session.commit()
        booking_id = booking.id
    opened, ended = sync_with_bookings(sessions, manager, now)
    assert opened == [booking_id] and ended == [], "five minutes ahead: the robots start now; not the later one"
    tutor = _login(server, "tutor1")
    state = _wait_until_ready(tutor, course_id)
    assert state["open"] and state["counts"]["ready"] == 2
    assert sync_with_bookings(sessions, manager, now) == ([], []), "one session per booking"

    with sessions() as session:
        session.execute(update(Booking).where(Booking.id == booking_id).values(
            starts_at=now - timedelta(minutes=61), ends_at=now - timedelta(minutes=1)))
        session.commit()
    opened, ended = sync_with_bookings(sessions, manager, now)
    assert opened == [] and len(ended) == 1
    status, state = _api(tutor, "GET", f"/api/courses/{course_id}/class-session")
    assert not state["open"] and manager.count() == 0, "the slot ended: every robot stopped"
    with sessions() as session:
        assert session.scalar(select(ClassSession.booking_id).where(ClassSession.id == ended[0])) == booking_id
