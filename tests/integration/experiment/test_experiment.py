"""The experiment against a real course-A skill server (fast mode) and the app on SQLite: delay API, trials."""

from __future__ import annotations

import json
import time
from pathlib import Path
from urllib.request import Request

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import create_server
from skill_server.sim.geometry import Pose2D
from tests.conftest import LabClient, LiveServer, make_test_app


@pytest.fixture(scope="module")
def course_robot():  # type: ignore[no-untyped-def]
    running = create_server(port=0, scene="course-A", realtime=False, robot_name="course-1")
    yield running
    running.stop(grace_s=0.5)


@pytest.fixture
def course_app(tmp_path: Path, course_robot):  # type: ignore[no-untyped-def]
    from middleware.access.coordinator import access_coordinator
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.robots.registry import robot_registry

    app = make_test_app(f"sqlite:///{tmp_path / 'x.sqlite3'}", f"course-1=127.0.0.1:{course_robot.port}", tmp_path)
    with session_factory(app)() as session:
        create_user(session, "tutor1", "tutor", "correct-horse-battery")
        session.commit()
    server = LiveServer(app)
    yield server
    server.stop()
    access_coordinator(app).stop_ticker()
    robot_registry(app).close()


def send_json(client: LabClient, method: str, path: str, body: object) -> tuple[int, dict]:
    token = client.csrf_token("/experiment")
    request = Request(client.base_url + path, data=json.dumps(body).encode(), method=method,
                      headers={"Content-Type": "application/json", "X-CSRFToken": token})
    try:
        with client._opener.open(request, timeout=10) as response:  # noqa: SLF001
            return response.status, json.loads(response.read())
    except Exception as error:  # urllib raises on 4xx
        return error.code, json.loads(error.read())  # type: ignore[attr-defined]


def get_json(client: LabClient, path: str) -> tuple[int, dict]:
    status, _, body = client.request("GET", path, headers={"Accept": "application/json"})
    return status, json.loads(body) if body.startswith("{") else {}


def test_the_course_rpcs_report_the_run_and_its_events(course_robot) -> None:  # type: ignore[no-untyped-def]
    with grpc.insecure_channel(f"127.0.0.1:{course_robot.port}") as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        run = stub.GetCourseRun(robot_pb2.GetCourseRunRequest(), timeout=5)
        assert run.is_course and run.scene_name == "course-A" and run.phase == "at_start"
        assert stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=5).scene_name == "course-A"


@pytest.mark.parametrize("hostile", [-1, 7.5, "NaN", "3", None, True, 1e308])
def test_a_tutor_is_refused_absurd_delays_naming_the_field(course_app, hostile: object) -> None:  # type: ignore[no-untyped-def]
    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", "correct-horse-battery") == 302
    status, body = send_json(tutor, "PUT", "/api/experiment/delays/student1", {"delay_s": hostile})
    assert status == 400 and body["error"]["field"] == "delay_s"


def test_students_may_not_set_delays_or_read_the_class_results(course_app) -> None:  # type: ignore[no-untyped-def]
    student = LabClient(course_app.url)
    assert student.login() == 302
    status, body = send_json(student, "PUT", "/api/experiment/delays/student1", {"delay_s": 1})
    assert status == 403
    assert get_json(student, "/api/experiment/results")[0] == 403


def test_a_student_runs_a_trial_on_course_a_and_the_tutor_sees_it(course_app, course_robot) -> None:  # type: ignore[no-untyped-def]
    student = LabClient(course_app.url)
    assert student.login() == 302
    status, state = get_json(student, "/api/experiment/state")
    assert status == 200 and state["robots"] == [{"name": "course-1", "scene": "course-A"}]
    status, body = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})
    assert status == 201
    trial = body["trial"]
    assert trial["course"] == "course-A" and trial["delay_s"] in (1.0, 3.0) and trial["status"] == "assigned"
    assert get_json(student, "/api/experiment/state")[1]["delay_s"] == trial["delay_s"]
    assert get_json(student, "/api/me/preferences/camera-feedback")[1]["value"] is trial["feedback"]

    # Finishing before the robot saw a run is refused.
    status, body = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 409 and body["error"]["code"] == "run_not_finished"

    world = course_robot.world
    time.sleep(0.01)
    for x in (-2.5, -2.0, 0.0, 2.4, 0.0, -2.45):
        world.set_pose(Pose2D(x, 0.0, 0.0))
        tick = world.snapshot.tick
        assert world.wait_for_snapshot(tick + 30, 5.0) is not None  # fast mode: the loop runs on by itself
    status, body = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 200, body
    assert body["trial"]["status"] == "completed" and body["trial"]["total_time_s"] > 0 and body["trial"]["errors"] == 0
    assert get_json(student, "/api/experiment/state")[1]["delay_s"] == 0.0

    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", "correct-horse-battery") == 302
    status, results = get_json(tutor, "/api/experiment/results")
    assert status == 200 and len(results["trials"]) == 1 and results["summary"][0]["n"] == 1
    status, _, csv_text = tutor.request("GET", "/experiment/results.csv")
    assert status == 200 and "student1" in csv_text and "course-A" in csv_text
