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
from tests.conftest import STUDENT_PASSWORD, LabClient, make_course, ready_for_trials, served_lab
from tests.integration.lab.test_skills_api import take_control


@pytest.fixture(scope="module")
def course_robot():
    running = create_server(port=0, scene="course-A", realtime=False, robot_name="course-1")
    yield running
    running.stop(grace_s=0.5)


@pytest.fixture
def course_app(tmp_path: Path, course_robot):
    """The lab with tutor1 teaching student1 (a tutor sets and reads only their own students' delays and trials)."""
    with served_lab(f"course-1=127.0.0.1:{course_robot.port}", tmp_path) as server:
        make_course(server.app, "EXP", {"tutor1": "tutor", "student1": "student"})
        ready_for_trials(server.app, "student1")
        yield server


def send_json(client: LabClient, method: str, path: str, body: object) -> tuple[int, dict]:
    token = client.csrf_token("/experiment")
    request = Request(client.base_url + path, data=json.dumps(body).encode(), method=method,
                      headers={"Content-Type": "application/json", "X-CSRFToken": token})
    try:
        with client._opener.open(request, timeout=10) as response:  # noqa: SLF001
            return response.status, json.loads(response.read())
    except Exception as error:  # urllib raises on 4xx
        return error.code, json.loads(error.read())


def get_json(client: LabClient, path: str) -> tuple[int, dict]:
    status, _, body = client.request("GET", path, headers={"Accept": "application/json"})
    return status, json.loads(body) if body.startswith("{") else {}


def test_the_track_rpcs_report_the_run_and_its_events(course_robot) -> None:
    with grpc.insecure_channel(f"127.0.0.1:{course_robot.port}") as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        run = stub.GetTrackRun(robot_pb2.GetTrackRunRequest(), timeout=5)
        assert run.is_track and run.scene_name == "course-A" and run.phase == "at_start"
        assert stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=5).scene_name == "course-A"


def test_the_robot_link_reads_the_track_run_and_says_when_a_scene_has_none(
    course_robot, skill_server_address: str
) -> None:
    from middleware.robots.link import RobotLink, RobotUnavailable

    for name, address, is_track in (("course-1", f"127.0.0.1:{course_robot.port}", True),
                                    ("lab-1", skill_server_address, False)):
        link = RobotLink(name, address, rpc_timeout_s=5.0)
        try:
            run = link.track_run()
            assert run.is_track is is_track
            assert run.scene_name == ("course-A" if is_track else "lab")
            assert link.restart_track_run().is_track is is_track  # off a track, a restart is a harmless no-op
        finally:
            link.close()
    ghost = RobotLink("ghost", "127.0.0.1:9", rpc_timeout_s=0.5)
    with pytest.raises(RobotUnavailable):
        ghost.track_run()
    ghost.close()


@pytest.mark.parametrize("hostile", [-1, 7.5, "NaN", "3", None, True, 1e308])
def test_a_tutor_is_refused_absurd_delays_naming_the_field(course_app, hostile: object) -> None:
    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", STUDENT_PASSWORD) == 302
    status, body = send_json(tutor, "PUT", "/api/experiment/delays/student1", {"delay_s": hostile})
    assert status == 400 and body["error"]["field"] == "delay_s"


def test_students_may_not_set_delays_or_read_the_class_results(course_app) -> None:
    student = LabClient(course_app.url)
    assert student.login() == 302
    status, body = send_json(student, "PUT", "/api/experiment/delays/student1", {"delay_s": 1})
    assert status == 403
    assert get_json(student, "/api/experiment/results")[0] == 403


def test_a_student_runs_a_trial_on_course_a_and_the_tutor_sees_it(course_app, course_robot) -> None:
    student = LabClient(course_app.url)
    assert student.login() == 302
    status, state = get_json(student, "/api/experiment/state")
    assert status == 200 and state["robots"] == [{"name": "course-1", "scene": "course-A", "own": False}]
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


@pytest.fixture
def course_and_lab_app(tmp_path: Path, course_robot, skill_server_address: str):
    with served_lab(f"course-1=127.0.0.1:{course_robot.port},lab-1={skill_server_address}", tmp_path) as server:
        ready_for_trials(server.app, "student1")
        yield server


def injected_delays_s(socket, seconds: float) -> list[float]:
    """The injected delays a telemetry socket announced within seconds."""
    announced = []
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        raw = socket.receive(timeout=left)
        if isinstance(raw, str) and '"injected_delay_s"' in raw:
            announced.append(json.loads(raw)["injected_delay_s"])
    return announced


def test_a_trial_s_delay_is_on_its_robot_s_video_only_and_ends_when_it_is_given_up(course_and_lab_app) -> None:
    student = LabClient(course_and_lab_app.url)
    assert student.login() == 302
    status, body = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})
    assert status == 201
    trial = body["trial"]
    on_course = student.websocket("/ws/robots/course-1/telemetry")
    on_lab = student.websocket("/ws/robots/lab-1/telemetry")
    assert injected_delays_s(on_course, 3.0) == [trial["delay_s"]]
    assert injected_delays_s(on_lab, 0.5) == []  # lab-1's video stays undelayed while the trial is open

    status, _ = send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/abandon", {})
    assert status == 200
    assert injected_delays_s(on_course, 3.0 + trial["delay_s"]) == [0.0]
    assert get_json(student, "/api/experiment/state")[1]["delay_s"] == 0.0


def test_after_giving_up_mid_run_the_next_trial_counts_the_next_run_from_a_and_is_recorded(
    course_app, course_robot
) -> None:
    student = LabClient(course_app.url)
    assert student.login() == 302
    queue = take_control(student, "course-1")
    world = course_robot.world

    def run_at(x_m: float) -> dict:
        world.set_pose(Pose2D(x_m, 0.0, 0.0))
        assert world.wait_for_snapshot(world.snapshot.tick + 30, 5.0) is not None
        return get_json(student, "/api/experiment/state")[1]["run"]

    first = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})[1]["trial"]
    run_at(-2.5)
    assert run_at(-2.0)["phase"] == "to_b" and run_at(0.0)["phase"] == "to_b"
    assert send_json(student, "POST", f"/api/experiment/trials/{first['id']}/abandon", {})[0] == 200

    # Giving up ended the robot's run too: nothing of it is left to finish, and the clock is not running.
    status, body = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})
    assert status == 201
    second = body["trial"]
    for x_m in (0.0, 2.4):  # driving on from mid-course starts nothing: a run begins at A
        run = run_at(x_m)
        assert run["phase"] == "return_to_a" and not run["finished"] and run["time_s"] == 0.0, run
        assert "back to A" in run["message"] and "began before your trial" not in run["message"]
    assert run_at(-2.45)["message"] == "The robot is at A (blue): drive off to start the clock."
    for x_m, phase in ((-2.0, "to_b"), (2.4, "to_a"), (-2.45, "finished")):
        run = run_at(x_m)
        assert run["phase"] == phase and "began before your trial" not in run["message"], run
    assert run["finished"] and run["message"].startswith("Finished in")
    status, body = send_json(student, "POST", f"/api/experiment/trials/{second['id']}/finish", {})
    queue.close()
    assert status == 200, body
    assert body["trial"]["status"] == "completed" and 0 < body["trial"]["total_time_s"] == pytest.approx(
        run["time_s"], abs=0.1)


def test_a_trial_begun_while_someone_else_drives_leaves_their_run_alone(course_app, course_robot) -> None:
    tutor = LabClient(course_app.url)
    assert tutor.login("tutor1", STUDENT_PASSWORD) == 302
    queue = take_control(tutor, "course-1")
    world = course_robot.world
    for x_m in (-2.45, -2.0):
        world.set_pose(Pose2D(x_m, 0.0, 0.0))
        assert world.wait_for_snapshot(world.snapshot.tick + 30, 5.0) is not None
    student = LabClient(course_app.url)
    assert student.login() == 302
    time.sleep(1.2)  # past the clock slack: the tutor's run began before the trial
    assert send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})[0] == 201
    run = get_json(student, "/api/experiment/state")[1]["run"]
    queue.close()
    assert run["phase"] == "to_b" and "began before your trial" in run["message"], run
