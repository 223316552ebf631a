"""Issue 34, item 12 and the results of item 19, against a real course-A skill server (fast mode) and the app on
SQLite: during a delay trial the robot is driven by hand whatever sends the command, the preview is the trial's,
every stream that shows the robot is delayed; a trial given up is not shown as recorded; a tutor reads the trials
that count for the courses they teach."""

from __future__ import annotations

import contextlib
import json
import time

import pytest
import simple_websocket
from sqlalchemy import select

from middleware.models import Course
from tests.conftest import STUDENT_PASSWORD, LabClient, add_test_account, make_course, ready_for_trials, served_lab
from tests.integration.experiment.test_experiment import (  # noqa: F401 (fixtures)
    course_app,
    course_robot,
    get_json,
    injected_delays_s,
    send_json,
)
from tests.integration.lab.test_skills_api import take_control

GO_TO_GOAL = "/api/robots/course-1/skills/go_to_goal/goals"


def _start_trial(student: LabClient, **body: object) -> dict:
    status, answer = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1", **body})
    assert status == 201, answer
    return answer["trial"]


def _give_up(student: LabClient, trial: dict) -> None:
    assert send_json(student, "POST", f"/api/experiment/trials/{trial['id']}/abandon", {})[0] == 200


def _goal_status(student: LabClient, goal_id: str) -> str:
    return get_json(student, f"/api/robots/course-1/goals/{goal_id}")[1]["goal"]["status"]


def test_during_a_trial_the_robot_is_driven_by_hand_whatever_sends_the_command(course_app) -> None:  # noqa: F811
    from middleware.access.commands import robot_commands
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.errors import Refused
    from protos.telelab.v1 import robot_pb2

    student = LabClient(course_app.url)
    assert student.login() == 302
    queue = take_control(student, "course-1")
    status, body = send_json(student, "POST", GO_TO_GOAL, {"parameters": {"goal_x_m": 2.4, "goal_y_m": 0.0},
                                                           "preempt": True})
    assert status == 202, body
    before = body["goal"]["goal_id"]

    trial = _start_trial(student)
    deadline = time.monotonic() + 5
    while _goal_status(student, before) not in ("canceled", "aborted", "succeeded") and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _goal_status(student, before) != "succeeded" and _goal_status(student, before) in ("canceled", "aborted")

    status, body = send_json(student, "POST", GO_TO_GOAL, {"parameters": {"goal_x_m": 2.4, "goal_y_m": 0.0},
                                                           "preempt": True})
    assert status == 409 and body["error"]["code"] == "hand_driving_only", body
    assert body["error"]["message"].startswith("Your delay trial on course-1 measures driving by hand")
    status, body = send_json(student, "POST", "/api/robots/course-1/dock", {})
    assert status == 409 and body["error"]["code"] == "hand_driving_only", body
    status, body = send_json(student, "POST", "/api/robots/course-1/skills/direct_control/goals",
                             {"parameters": {"linear_mps": 0.1, "angular_radps": 0.0, "duration_s": 0.2},
                              "preempt": True})
    assert status == 202, body  # driving by hand is what the trial measures
    with course_app.app.app_context(), session_factory(course_app.app)() as session:
        user_id = find_user(session, "student1").id
        robot = robot_commands(course_app.app).for_user("course-1", user_id)
        for source in (lambda: robot.run_plan("tour", robot_pb2.PlanBlock(), preempt=True),  # a plan, a cue, a tour
                       lambda: robot.place_robot(robot_pb2.Pose2D(x_m=2.4)),
                       lambda: robot.activate("go_to_goal", {"goal_x_m": 2.4}, preempt=True)):
            with pytest.raises(Refused) as refused:
                source()
            assert refused.value.code == "hand_driving_only"

    _give_up(student, trial)
    status, body = send_json(student, "POST", GO_TO_GOAL, {"parameters": {"goal_x_m": -2.4, "goal_y_m": 0.0},
                                                           "preempt": True})
    assert status == 202, body  # the trial over, go-to-goal is back
    queue.close()


def test_the_motion_preview_is_the_trial_s_until_it_ends(course_app) -> None:  # noqa: F811
    student = LabClient(course_app.url)
    assert student.login() == 302
    assert get_json(student, "/api/me/preferences/camera-feedback")[1] == {"value": None, "locked": None}
    trial = _start_trial(student)
    shown = "on" if trial["feedback"] else "off"
    status, body = get_json(student, "/api/me/preferences/camera-feedback")
    assert status == 200 and body["value"] is trial["feedback"]
    assert body["locked"] == f"Your delay trial sets the motion preview {shown} until it is recorded or given up."
    status, body = send_json(student, "PUT", "/api/me/preferences/camera-feedback", {"value": not trial["feedback"]})
    assert status == 409 and body["error"]["code"] == "preference_locked" and body["error"]["field"] == "value"
    assert get_json(student, "/api/me/preferences/camera-feedback")[1]["value"] is trial["feedback"]
    assert send_json(student, "PUT", "/api/me/preferences/camera-feedback-fill", {"value": "black"})[0] == 200

    _give_up(student, trial)
    assert send_json(student, "PUT", "/api/me/preferences/camera-feedback", {"value": True})[0] == 200
    assert get_json(student, "/api/me/preferences/camera-feedback")[1] == {"value": True, "locked": None}


def test_the_localization_stream_is_delayed_during_a_trial_as_the_camera_is(course_app) -> None:  # noqa: F811
    student = LabClient(course_app.url)
    assert student.login() == 302
    trial = _start_trial(student)
    localization = student.websocket("/ws/robots/course-1/localization")
    try:
        assert injected_delays_s(localization, 3.0) == [trial["delay_s"]]
        _give_up(student, trial)
        assert injected_delays_s(localization, 3.0 + trial["delay_s"]) == [0.0]
    finally:  # its reader thread kept the run alive a minute after the last test
        with contextlib.suppress(simple_websocket.ConnectionClosed):
            localization.close()


def test_after_giving_up_the_page_s_state_names_the_trial_given_up_not_the_one_recorded_before(
        course_app) -> None:  # noqa: F811
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.experiment import services

    student = LabClient(course_app.url)
    assert student.login() == 302
    recorded = _start_trial(student)
    with session_factory(course_app.app)() as session:
        services.finish_trial(session, find_user(session, "student1"), recorded["id"], services.RunResult(21.5, 1))
        session.commit()
    assert get_json(student, "/api/experiment/state")[1]["last_trial"]["status"] == "completed"
    given_up = _start_trial(student)
    _give_up(student, given_up)
    last = get_json(student, "/api/experiment/state")[1]["last_trial"]
    assert (last["id"], last["status"]) == (given_up["id"], "abandoned")


@pytest.fixture
def two_courses(tmp_path, course_robot):  # noqa: F811
    """student1 in course X (tutor1) and in course Y (tutor2); an admin."""
    from middleware.db import session_factory

    with served_lab(f"course-1=127.0.0.1:{course_robot.port}", tmp_path) as server:
        with session_factory(server.app)() as session:
            add_test_account(session, "tutor2", "tutor")
            add_test_account(session, "root", "admin")
            session.commit()
        x = make_course(server.app, "X", {"tutor1": "tutor", "student1": "student"})
        y = make_course(server.app, "Y", {"tutor2": "tutor", "student1": "student"})
        ready_for_trials(server.app, "student1")
        yield server, x, y


def test_a_tutor_reads_only_the_trials_that_count_for_a_course_they_teach(two_courses) -> None:
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.experiment import services

    server, x, y = two_courses
    student = LabClient(server.url)
    assert student.login() == 302
    state = get_json(student, "/api/experiment/state")[1]
    assert [c["code"] for c in state["courses"]] == ["X", "Y"]
    status, body = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1"})
    assert status == 400 and body["error"]["field"] == "course_id", body  # in two courses: say which
    for hostile in (999, "1", True, -1):
        status, body = send_json(student, "POST", "/api/experiment/trials", {"robot_name": "course-1",
                                                                               "course_id": hostile})
        assert status == 400 and body["error"]["field"] == "course_id", (hostile, body)
    trial = _start_trial(student, course_id=x)
    with session_factory(server.app)() as session:
        services.finish_trial(session, find_user(session, "student1"), trial["id"], services.RunResult(30.0, 2))
        session.commit()

    def seen_by(name: str) -> list[int]:
        reader = LabClient(server.url)
        assert reader.login(name, STUDENT_PASSWORD) == 302
        status, results = get_json(reader, "/api/experiment/results")
        assert status == 200
        _, _, csv_text = reader.request("GET", "/experiment/results.csv")
        assert csv_text.count("student1") == len(results["trials"])
        return [t["id"] for t in results["trials"]]

    assert seen_by("tutor1") == [trial["id"]]
    assert seen_by("tutor2") == []  # student1's tutor in course Y, not in course X
    assert seen_by("root") == [trial["id"]]


def _ack_after_s(drive, sequence: int) -> float:
    """Seconds from sending a drive command to its acknowledgement on the drive socket."""
    sent = time.monotonic()
    drive.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": 0.0, "angular_radps": 0.1}))
    while True:
        message = json.loads(drive.receive(timeout=10))
        if message.get("type") == "ack" and message["sequence"] == sequence:
            return time.monotonic() - sent


def test_a_trial_of_a_course_whose_protocol_delays_commands_holds_the_drivers_commands_for_its_delay(
        course_app) -> None:  # noqa: F811
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.experiment import protocol

    student = LabClient(course_app.url)
    assert student.login() == 302
    queue = take_control(student, "course-1")
    drive = student.websocket("/ws/robots/course-1/drive")
    assert json.loads(drive.receive(timeout=10))["type"] == "ready"
    assert _ack_after_s(drive, 1) < 0.5, "no trial: commands go at once"
    with session_factory(course_app.app)() as session:
        tutor = find_user(session, "tutor1")
        course_id = session.scalars(select(Course.id).where(Course.code == "EXP")).one()
        protocol.set_protocol(session, tutor, course_id, {"delay_commands": True})
        session.commit()
    trial = _start_trial(student)
    assert trial["commands_delayed"] and trial["delay_s"] == 1.0, trial  # the ready student runs row 1: 1 s first
    time.sleep(1.2)  # the drive channel reads the delay in force at most once a second
    held = [_ack_after_s(drive, sequence) for sequence in (2, 3)]
    assert all(0.9 <= seconds < 2.5 for seconds in held), held
    _give_up(student, trial)
    time.sleep(1.2)
    assert _ack_after_s(drive, 4) < 0.5, "the trial given up, commands go at once again"
    drive.close()
    queue.close()
