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
from tests.conftest import STUDENT_PASSWORD, LabClient, served_lab
from tests.integration.middleware.test_skills_api import take_control


@pytest.fixture(scope="module")
def course_robot():  # type: ignore[no-untyped-def]
    running = create_server(port=0, scene="course-A", realtime=False, robot_name="course-1")
    yield running
    running.stop(grace_s=0.5)


@pytest.fixture
def course_app(tmp_path: Path, course_robot):  # type: ignore[no-untyped-def]
    with served_lab(f"course-1=127.0.0.1:{course_robot.port}", tmp_path) as server:
        yield server


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


def test_the_robot_link_reads_the_course_run_and_says_when_a_scene_has_none(  # type: ignore[no-untyped-def]
    course_robot, skill_server_address: str
) -> None:
    from middleware.robots.link import RobotLink, RobotUnavailable

    for name, address, is_course in (("course-1", f"127.0.0.1:{course_robot.port}", True),
                                     ("lab-1", skill_server_address, False)):
        link = RobotLink(name, address, rpc_timeout_s=5.0)
        try:
            run = link.course_run()
            assert run.is_course is is_course
            assert run.scene_name == ("course-A" if is_course else "lab")
        finally:
            link.close()
    ghost = RobotLink("ghost", "127.0.0.1:9", rpc_timeout_s=0.5)
    with pytest.raises(RobotUnavailable):
        ghost.course_run()
    ghost.close()


@pytest.mark.parametrize("hostile", [-1, 7.5, "NaN", "3", None, True, 1e308])
def test_a_tutor_is_refused_absurd_delays_naming_the_field(course_app, hostile: object) -> None:  # type: ignore[no-untyped-def]
    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", STUDENT_PASSWORD) == 302
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

    # Only the robot's controller records a run; finishing before the robot saw one is refused.
    status, body = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 403 and body["error"]["code"] == "not_controller"
    queue = take_control(student, "course-1")
    status, body = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 409 and body["error"]["code"] == "run_not_finished"

    world = course_robot.world
    time.sleep(0.01)
    # The state the page polls follows the run as it happens: off A, at B, back at A.
    for x, phase in ((-2.5, "at_start"), (-2.0, "to_b"), (0.0, "to_b"), (2.4, "to_a"), (0.0, "to_a"),
                     (-2.45, "finished")):
        world.set_pose(Pose2D(x, 0.0, 0.0))
        tick = world.snapshot.tick
        assert world.wait_for_snapshot(tick + 30, 5.0) is not None  # fast mode: the loop runs on by itself
        run = get_json(student, "/api/experiment/state")[1]["run"]
        assert run["online"] and run["phase"] == phase and run["finished"] is (phase == "finished"), (x, run)
    assert run["message"].startswith("Finished in") and run["errors"] == 0 and run["time_s"] > 0
    status, body = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 200, body
    queue.close()
    assert body["trial"]["status"] == "completed" and body["trial"]["total_time_s"] > 0 and body["trial"]["errors"] == 0
    state = get_json(student, "/api/experiment/state")[1]
    assert state["delay_s"] == 0.0 and state["trial"] is None and state["run"] is None
    assert state["last_trial"]["id"] == trial["id"] and state["robots"]

    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", STUDENT_PASSWORD) == 302
    status, results = get_json(tutor, "/api/experiment/results")
    assert status == 200 and len(results["trials"]) == 1 and results["summary"][0]["n"] == 1
    status, _, csv_text = tutor.request("GET", "/experiment/results.csv")
    assert status == 200 and "student1" in csv_text and "course-A" in csv_text
