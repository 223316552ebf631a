"""Class sessions: a tutor starts one for a course of 10 students, each gets a distinct robot of their own that
nobody else reaches, and ending the session stops them all; on SQLite and on PostgreSQL, with real robots."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, add_test_account, make_course, make_test_app
from tests.integration.teaching.test_practice_console_and_uploads import CHANNELS, _api, refusal

STUDENTS = [f"s{i:02}" for i in range(1, 11)]


@pytest.fixture
def class_lab(database_url: str, tmp_path: Path, skill_server_address: str) -> Iterator[tuple[LiveServer, int]]:
    """The app with tutor1 teaching a course of 10 students, tutor2 teaching nothing, and an empty course."""
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager
    from tests.conftest import _let_go

    app = make_test_app(database_url, f"lab-1={skill_server_address}", tmp_path)
    with session_factory(app)() as session:
        for name in ["tutor1", "tutor2"]:
            add_test_account(session, name, "tutor")
        for name in STUDENTS:
            add_test_account(session, name, "student")
        session.commit()
    course_id = make_course(app, "ROB101", {"tutor1": "tutor", **dict.fromkeys(STUDENTS, "student")})
    make_course(app, "EMPTY1", {"tutor1": "tutor"})
    server = LiveServer(app)
    try:
        yield server, course_id
    finally:
        practice_manager(app).shutdown()
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()


def _login(server: LiveServer, name: str) -> LabClient:
    client = LabClient(server.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def _wait_until_ready(tutor: LabClient, course_id: int, timeout_s: float = 90) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        status, state = _api(tutor, "GET", f"/api/courses/{course_id}/class-session")
        assert status == 200, state
        if state["counts"]["starting"] == 0:
            return state
        time.sleep(0.5)
    pytest.fail(f"the class's robots were not all started within {timeout_s:.0f} s: {state}")


def test_every_student_gets_a_distinct_robot_nobody_else_reaches_and_ending_stops_them(class_lab) -> None:
    from middleware.farm.setup import robot_farm
    from middleware.teaching.practice_robots import practice_manager

    server, course_id = class_lab
    tutor = _login(server, "tutor1")
    status, opened = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
    assert status == 201 and opened["open"] and len(opened["seats"]) == 10, opened
    state = _wait_until_ready(tutor, course_id)
    assert state["counts"] == {"starting": 0, "ready": 10, "failed": 0, "stopped": 0}, state
    assert sorted(seat["robot"] for seat in state["seats"]) == [f"practice-{name}" for name in STUDENTS]
    farm = robot_farm(server.app)
    addresses = {robot.address for robot in farm.robots()}
    assert len(addresses) == 10  # ten robots, not one shared

    first, second = _login(server, "s01"), _login(server, "s02")
    status, seat = _api(first, "GET", "/api/class-session")
    assert status == 200 and seat["state"] == "ready" and seat["robot"] == "practice-s01"
    assert seat["console_url"] == "/lab/practice-s01" and seat["course"]["code"] == "ROB101"
    assert first.request("GET", "/lab/practice-s01")[0] == 200
    status, ran = _api(first, "POST", "/api/practice/commands", {"command": {"stop": True}})
    assert status == 202 and ran["robot"] == "practice-s01"
    assert second.request("GET", "/lab/practice-s01")[0] == 404
    for method, path in [("GET", "/api/robots/practice-s01"), ("GET", "/api/robots/practice-s01/panels"),
                         ("GET", "/api/robots/practice-s01/map"), ("GET", "/api/robots/practice-s01/chat")]:
        status, error = _api(second, method, path)
        assert (status, error["error"]["code"]) == (404, "unknown_robot"), path
    for channel in CHANNELS:
        assert refusal(second, f"/ws/robots/practice-s01/{channel}") == ("unknown_robot", 4404), channel
    status, error = _api(first, "GET", f"/api/courses/{course_id}/class-session")
    assert status == 403  # a student does not see the class's seats

    # Five students stop their robots at once: the tutor's view says so at once (issue 34, item 7: the seats kept
    # saying "ready" and their links led to a 404), their pages offer a restart, and five restarts at once work.
    stoppers = [_login(server, name) for name in STUDENTS[:5]]
    with ThreadPoolExecutor(5) as pool:
        stopped = list(pool.map(lambda client: _api(client, "DELETE", "/api/practice"), stoppers))
    assert all(status == 200 and body["stopped"] for status, body in stopped), stopped
    status, state = _api(tutor, "GET", f"/api/courses/{course_id}/class-session")
    assert state["counts"] == {"starting": 0, "ready": 5, "failed": 0, "stopped": 5}, state
    assert {seat["username"] for seat in state["seats"] if seat["state"] == "stopped"} == set(STUDENTS[:5])
    for client in stoppers:
        status, seat = _api(client, "GET", "/api/class-session")
        assert seat["state"] == "stopped" and seat["console_url"] is None, seat
    with ThreadPoolExecutor(5) as pool:
        restarted = list(pool.map(lambda client: _api(client, "POST", "/api/class-session/robot"), stoppers))
    assert all(status == 202 and body["state"] == "starting" for status, body in restarted), restarted
    state = _wait_until_ready(tutor, course_id)
    assert state["counts"] == {"starting": 0, "ready": 10, "failed": 0, "stopped": 0}, state
    status, error = _api(stoppers[0], "POST", "/api/class-session/robot")
    assert (status, error["error"]["code"]) == (409, "robot_running")
    assert len({robot.address for robot in farm.robots()}) == 10

    # The session's robots are not idle while it is open, whatever their last use.
    manager = practice_manager(server.app)
    manager.idle_s, idle_s = 0.0, manager.idle_s
    try:
        assert manager.stop_idle() == []
    finally:
        manager.idle_s = idle_s
    status, ended = _api(tutor, "DELETE", f"/api/courses/{course_id}/class-session")
    assert status == 200 and not ended["open"]
    assert farm.robots() == [] and practice_manager(server.app).count() == 0
    status, seat = _api(first, "GET", "/api/class-session")
    assert status == 200 and not seat["open"]
    assert first.request("GET", "/lab/practice-s01")[0] == 404


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_bad_requests_are_clear_and_leave_nothing_started(class_lab) -> None:
    from middleware.db import session_factory
    from middleware.farm.ray_farm import RayFarm
    from middleware.models import ClassSession
    from middleware.teaching.practice_robots import practice_manager

    server, course_id = class_lab
    tutor, stranger = _login(server, "tutor1"), _login(server, "tutor2")
    status, error = _api(tutor, "POST", "/api/courses/999/class-session")
    assert (status, error["error"]["code"]) == (404, "unknown_course")
    status, error = _api(stranger, "POST", f"/api/courses/{course_id}/class-session")
    assert status == 403 and "courses you teach" in error["error"]["message"]
    assert stranger.request("GET", f"/courses/{course_id}/class")[0] == 403
    status, error = _api(tutor, "POST", f"/api/courses/{course_id + 1}/class-session")
    assert (status, error["error"]["code"]) == (409, "no_students")
    status, error = _api(tutor, "DELETE", f"/api/courses/{course_id}/class-session")
    assert (status, error["error"]["code"]) == (409, "no_class_session")

    manager = practice_manager(server.app)
    with socket.socket() as unused:
        unused.bind(("127.0.0.1", 0))
        port = unused.getsockname()[1]
    real_farm, manager.farm = manager.farm, RayFarm(f"127.0.0.1:{port}")
    try:
        status, error = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
        assert (status, error["error"]["code"]) == (503, "farm_unavailable")
        assert "cannot be reached" in error["error"]["message"]
    finally:
        manager.farm = real_farm
    manager.cap = 5
    status, error = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
    assert (status, error["error"]["code"]) == (409, "farm_full") and "needs 10" in error["error"]["message"]
    with session_factory(server.app)() as session:
        assert session.query(ClassSession).count() == 0  # nothing half-started

    manager.cap = None
    status, _ = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
    assert status == 201
    status, error = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
    assert (status, error["error"]["code"]) == (409, "class_session_open")
    _wait_until_ready(tutor, course_id)
