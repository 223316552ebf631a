"""A robot's health and recovery over HTTP against a real skill server process: who may read and act (tutors and
admins on a lab robot, a tutor on a student's own robot only in a course they teach), the restart that brings the
robot back on its address with its maintenance logged, and hostile input refused naming the field."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from sqlalchemy.orm import Session

from tests.conftest import LabClient, add_test_account, served_lab
from tests.integration.teaching.test_practice_console_and_uploads import _api


@pytest.fixture(scope="module")
def robot_process() -> Iterator[str]:
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    robot = SkillServerProcess("lab-1", "lab", echo=False)
    robot.start()
    try:
        wait_until_serving(robot.address)
        yield robot.address
    finally:
        robot.stop()


@pytest.fixture
def lab(tmp_path, robot_process: str):
    from middleware.db import session_factory

    with served_lab(f"lab-1={robot_process}", tmp_path) as server:
        with session_factory(server.app)() as session:
            add_test_account(session, "root", "admin")
            session.commit()
        yield server


def _client(lab, name: str) -> LabClient:
    from tests.conftest import STUDENT_PASSWORD

    client = LabClient(lab.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def test_tutors_and_admins_read_a_lab_robots_health_restart_it_and_the_log_says_who(lab) -> None:
    student, tutor, admin = _client(lab, "student1"), _client(lab, "tutor1"), _client(lab, "root")
    for path in ("/api/robots/lab-1/health",):
        status, refused = _api(student, "GET", path)
        assert (status, refused["error"]["code"]) == (403, "forbidden")
    assert student.request("GET", "/robots/lab-1/health")[0] == 403
    assert _api(student, "POST", "/api/robots/lab-1/maintenance", {"action": "dock"})[0] == 403
    assert _api(tutor, "GET", "/api/robots/nosuch/health")[0] == 404
    for hostile in ({"action": "reboot"}, {"action": 1}, {}, {"action": None}):
        status, refused = _api(tutor, "POST", "/api/robots/lab-1/maintenance", hostile)
        assert (status, refused["error"]["field"]) == (400, "action"), hostile

    status, before = _api(tutor, "GET", "/api/robots/lab-1/health")
    assert status == 200 and before["health"]["online"] and before["health"]["restartable"], before
    assert before["health"]["real_time_factor"] > 0 and before["health"]["version"]
    status, docked = _api(admin, "POST", "/api/robots/lab-1/maintenance", {"action": "dock"})
    assert status == 200 and "dock" in docked["message"]
    status, answer = _api(tutor, "POST", "/api/robots/lab-1/maintenance", {"action": "restart"})
    assert status == 200 and answer["restarting"], answer
    deadline = time.monotonic() + 30
    while True:
        status, after = _api(tutor, "GET", "/api/robots/lab-1/health")
        if after["health"].get("online") and after["health"]["restarts"] == before["health"]["restarts"] + 1:
            break
        assert time.monotonic() < deadline, after
        time.sleep(0.3)
    assert after["health"]["pid"] == before["health"]["pid"]
    assert [(e["actor"], e["action"]) for e in after["maintenance"]] == [("tutor1", "restart"), ("root", "dock")]


def test_a_tutor_maintains_a_students_own_robot_only_in_a_course_they_teach(lab) -> None:
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.errors import Refused
    from middleware.lab.maintenance import require_maintainer
    from tests.conftest import make_course

    with session_factory(lab.app)() as session:
        add_test_account(session, "tutor2", "tutor")
        session.commit()
    make_course(lab.app, "R1", {"tutor1": "tutor", "student1": "student"})
    with Session(bind=session_factory(lab.app)().get_bind()) as session:
        owner = find_user(session, "student1").id
        require_maintainer(session, find_user(session, "tutor1"), owner)
        require_maintainer(session, find_user(session, "root"), owner)
        for outsider in ("tutor2", "student1"):
            with pytest.raises(Refused) as refused:
                require_maintainer(session, find_user(session, outsider), owner)
            assert refused.value.status == 403
