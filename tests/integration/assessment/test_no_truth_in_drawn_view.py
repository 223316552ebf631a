"""During an experimental attempt the robot's-eye view drawn by the browser reads nothing a student could take the
robot's true pose from (issue 17, item 4): its inputs are the scene route (the static world), and the telemetry
channel, on its own socket or on the page's link (/ws/link), whose only pose is odometry's once the attempt began
(outside graded runs it also carries `camera_pose`, where the robot stands, for the drawn camera). Checked on the real
skill server while the student drives through the attempt, with the teaching mode set to show students the ground
truth elsewhere (the localization panel), so no role rule hides a leak here.

Every dict shaped like a pose ({x_m, y_m, theta_rad}) in what the student receives is found by walking the
messages, and must sit at a path on the allowed list: a pose field added later fails this test until it is
judged.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import drive_for, receive_json

POSE_KEYS = {"x_m", "y_m", "theta_rad"}
TRUTH_KEYS = {"ground_truth", "true_pose", "truth", "position_error_m", "heading_error_rad",
              "odometry_position_error_m", "odometry_heading_error_rad"}


def pose_paths(value: object, path: str = "") -> Iterator[str]:
    """The dotted paths of every pose-shaped dict in value (list items as [])."""
    if isinstance(value, dict):
        if value.keys() >= POSE_KEYS:
            yield path
        for key, item in value.items():
            yield from pose_paths(item, f"{path}.{key}" if path else key)
    elif isinstance(value, list):
        for item in value:
            yield from pose_paths(item, f"{path}[]")


def truth_keys(value: object) -> set[str]:
    """Keys naming the ground truth or an error measured against it, anywhere in value, that carry a value."""
    found: set[str] = set()
    if isinstance(value, dict):
        found |= {key for key, item in value.items() if key in TRUTH_KEYS and item is not None}
        for item in value.values():
            found |= truth_keys(item)
    elif isinstance(value, list):
        for item in value:
            found |= truth_keys(item)
    return found


def open_attempt(app, client_as, course_people) -> tuple[object, int]:
    """An experimental exam on lab-1 and student1's attempt at it, with student1 in control; (student, attempt id)."""
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam
    from middleware.db import session_factory
    from middleware.models import User

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        tutor = session.get(User, course_people["tutor1"])
        exam = bank.create_exam(session, tutor, course_people["course"], parse_exam({
            "title": "Where are you?", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "task_kind": "reach_point",
            "x_m": 0.0, "y_m": 0.0, "rubric": "0.1:1, 2:0.25", "task_points": 10, "robot_name": "lab-1"}))
        session.commit()
        exam_id = exam.id
    return client_as("student1"), exam_id


def test_the_drawn_views_inputs_carry_only_odometry_during_an_attempt(app, client_as, course_people) -> None:
    roles = app.config["GROUND_TRUTH_ROLES"]
    app.config["GROUND_TRUTH_ROLES"] = roles | {"student"}
    try:
        student, exam_id = open_attempt(app, client_as, course_people)
        status, scene_before = api(student, "GET", "/api/robots/lab-1/scene")
        assert status == 200
        drive = student.websocket("/ws/robots/lab-1/drive")
        assert receive_json(drive)["type"] == "ready"

        telemetry = student.websocket("/ws/robots/lab-1/telemetry")
        before = [json.loads(text) for text in texts_for(telemetry, 0.5)]
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        attempt_id = answer["attempt"]["id"]
        texts_for(telemetry, 1.5)  # the socket open before the attempt hears of it within GRADED_RUN_RECHECK_S
        link = student.websocket("/ws/link")
        link.send(json.dumps({"type": "subscribe", "sub": 1, "path": "/ws/robots/lab-1/telemetry"}))
        driver = threading.Thread(target=drive_for, args=(drive, 2.0, 0.2, 0.4, 1))
        driver.start()
        direct: list[dict] = []
        linked: list[dict] = []
        while driver.is_alive():  # both read as a browser does, so neither socket drops what it was sent
            direct += [json.loads(text) for text in texts_for(telemetry, 0.05)]
            linked += [json.loads(text.partition(" ")[2]) for text in texts_for(link, 0.05) if text.startswith("1 ")]
        driver.join()
        status, scene_during = api(student, "GET", "/api/robots/lab-1/scene")
        status_submit, answer = api(student, "POST", f"/api/attempts/{attempt_id}/submit")
        drive.close()
        telemetry.close()
        link.close()
    finally:
        app.config["GROUND_TRUTH_ROLES"] = roles
    assert status_submit == 200, answer

    # The scene is the static world: the same answer while the robot moves, its one pose the scene's spawn.
    assert status == 200 and scene_during == scene_before
    assert set(pose_paths(scene_during)) == {"spawn"} and not truth_keys(scene_during)

    # Before the attempt the drawn camera is told where the robot stands (a camera shows the world as it is); once
    # it begins, on both sockets, it is not: the panel shows the server's camera instead (issue 34, item 11).
    shown = [message for message in before if message.get("type") == "telemetry"]
    assert shown and all(message["camera_pose"].keys() >= POSE_KEYS for message in shown)
    for name, messages in (("telemetry socket", direct), ("link", linked)):
        assert all(message.get("camera_pose") is None for message in messages), f"the {name} sent the camera pose"
        poses = [message for message in messages if message.get("type") == "telemetry"]
        assert len(poses) >= 10, f"the {name} brought {len(poses)} telemetry messages in 2 s"
        for message in messages:
            assert not truth_keys(message), f"the {name} sent the ground truth: {message}"
            allowed = {"odometry.pose"} if message.get("type") == "telemetry" else set()
            assert set(pose_paths(message)) <= allowed, f"the {name} sent a pose other than odometry's: {message}"
        # What the drawn view reads (drawn-view.js: telemetry.odometry.pose) is there in every message, and moved.
        assert all(message["odometry"]["pose"].keys() >= POSE_KEYS for message in poses)
        assert poses[0]["odometry"]["pose"] != poses[-1]["odometry"]["pose"]


def texts_for(ws, seconds: float) -> list[str]:
    """The text messages that reach ws within seconds."""
    texts: list[str] = []
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        message = ws.receive(timeout=left)
        if isinstance(message, str):
            texts.append(message)
    return texts


def test_the_localization_panel_hides_the_truth_once_a_graded_run_begins(app, client_as, course_people) -> None:
    roles = app.config["GROUND_TRUTH_ROLES"]
    app.config["GROUND_TRUTH_ROLES"] = roles | {"student"}  # a teaching mode that shows students the truth
    try:
        student, exam_id = open_attempt(app, client_as, course_people)
        drive = student.websocket("/ws/robots/lab-1/drive")
        assert receive_json(drive)["type"] == "ready"
        localization = student.websocket("/ws/robots/lab-1/localization")
        before = [json.loads(text) for text in texts_for(localization, 1.0)]
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        started = time.monotonic()
        texts_for(localization, 2.0)  # the panel, open all along, hears of the attempt within a second
        after = [json.loads(text) for text in texts_for(localization, 1.0)]
        waited_s = time.monotonic() - started
        status_submit, _ = api(student, "POST", f"/api/attempts/{answer['attempt']['id']}/submit")
        reopened = student.websocket("/ws/robots/lab-1/localization")  # after the attempt the teaching mode rules
        again = [json.loads(text) for text in texts_for(reopened, 1.0)]
        for ws in (drive, localization, reopened):
            ws.close()
    finally:
        app.config["GROUND_TRUTH_ROLES"] = roles
    assert status_submit == 200
    before, after, again = ([m for m in messages if m["type"] == "localization"] for messages in (before, after, again))
    assert before and all(truth_keys(message) for message in before), "the teaching mode showed the truth before"
    assert after and not any(truth_keys(message) for message in after), f"truth shown {waited_s:.1f} s into the run"
    assert again and all(truth_keys(message) for message in again)
