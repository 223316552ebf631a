"""While a student's obstacle-zone test is in progress nothing the middleware sends them shows the scene's obstacles
(issue 16; middleware/assessment/hidden_obstacles.py), on the real skill server: the scene route answers the walls
only, under a version of its own; the robot description leaves the obstacle boxes out; the map and the camera are
refused, on the camera's own socket and on the page's link (/ws/link), and a camera already open closes. A tutor and
another student meanwhile see everything, and the student sees everything again once the attempt ends (submitted, or
its deadline passed)."""

from __future__ import annotations

import json
import time
from datetime import UTC, datetime, timedelta

from middleware.assessment.hidden_obstacles import RECHECK_S
from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import closed_with, receive_json

SCENE = "/api/robots/lab-1/scene"
CAMERA = "/ws/robots/lab-1/camera"


def zone_exam(tutor, course_id: int) -> int:
    """An obstacle-zone test on lab-1, open now; its id."""
    now = datetime.now(UTC)
    status, answer = api(tutor, "POST", f"/api/courses/{course_id}/exams", {
        "title": "Find the obstacles", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
        "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 900, "task_kind": "obstacle_zone",
        "task_points": 10, "robot_name": "lab-1"})
    assert status == 201, answer
    return int(answer["exam"]["id"])


def obstacle_names(scene: dict) -> set[str]:
    """The names of the blocks and cylinders of a scene that are not walls."""
    return {body["name"] for body in scene["blocks"] + scene["cylinders"] if not body["name"].startswith("wall")}


def wall_names(scene: dict) -> set[str]:
    return {body["name"] for body in scene["blocks"] if body["name"].startswith("wall")}


def camera_frame_arrives(ws, within_s: float = 5.0) -> bool:
    """Whether a JPEG frame reaches ws within within_s."""
    deadline = time.monotonic() + within_s
    while (left := deadline - time.monotonic()) > 0:
        if isinstance(ws.receive(timeout=left), bytes):
            return True
    return False


def first_error(ws, timeout_s: float = 5.0) -> dict:
    """The first error message on ws; the stream's status messages (robot online, added delay) are skipped."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        message = receive_json(ws, timeout_s=left)
        if message.get("type") == "error":
            return message
    raise AssertionError("no error message arrived")


def link_camera(client) -> tuple[dict | None, dict | None, bool]:
    """The camera subscribed on a /ws/link of client: (the channel's first error message, its close on sub 0, whether
    a frame came), once it closed or a frame came."""
    link = client.websocket("/ws/link")
    link.send(json.dumps({"type": "subscribe", "sub": 1, "path": CAMERA}))
    said = closed = None
    framed = False
    deadline = time.monotonic() + 10.0
    while closed is None and not framed and (left := deadline - time.monotonic()) > 0:
        message = link.receive(timeout=left)
        if isinstance(message, bytes):
            framed = int.from_bytes(message[:4], "big") == 1
            continue
        if not isinstance(message, str):
            continue
        sub, _, text = message.partition(" ")
        payload = json.loads(text)
        if sub == "1" and said is None and payload.get("type") == "error":
            said = payload
        elif sub == "0" and payload.get("type") == "closed" and payload.get("sub") == 1:
            closed = payload
    link.close()
    return said, closed, framed


def test_a_zone_test_hides_the_obstacles_from_its_student_until_it_is_submitted(app, client_as,
                                                                               course_people) -> None:
    tutor, student, other = client_as("tutor1"), client_as("student1"), client_as("student2")
    exam_id = zone_exam(tutor, course_people["course"])
    status, full = api(student, "GET", SCENE)
    assert status == 200 and obstacle_names(full) >= {"crate", "cabinet", "bench", "pillar"}, full
    watching = student.websocket(CAMERA)  # open before the test begins
    assert camera_frame_arrives(watching)
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    try:
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        attempt_id = answer["attempt"]["id"]

        # The camera open all along hears of the test within seconds, and closes with its sentence.
        said = first_error(watching, timeout_s=8.0)
        assert said["code"] == "obstacles_hidden" and "obstacle-zone test" in said["message"], said
        assert closed_with(watching) == 4403

        status, hidden = api(student, "GET", SCENE)
        assert status == 200 and not obstacle_names(hidden) and hidden["cylinders"] == []
        assert wall_names(hidden) == wall_names(full) and len(wall_names(full)) == 4
        assert "obstacle-zone test" in hidden["obstacles_hidden"] and hidden["version"] != full["version"]
        # A page holding the full scene is not told to keep it.
        status, headers, body = student.request("GET", SCENE, headers={"If-None-Match": f'"{full["version"]}"'})
        assert status == 200 and not obstacle_names(json.loads(body)), status
        assert headers["ETag"] != f'"{full["version"]}"'

        status, robot = api(student, "GET", "/api/robots/lab-1")
        assert status == 200 and robot["info"]["obstacles_hidden"]
        assert {box["name"] for box in robot["info"]["scene_boxes"]} == wall_names(full)
        status, refused = api(student, "GET", "/api/robots/lab-1/map")
        assert status == 403 and refused["error"]["code"] == "obstacles_hidden", refused

        camera = student.websocket(CAMERA)
        said = first_error(camera)
        assert said["code"] == "obstacles_hidden", said
        assert closed_with(camera) == 4403
        said, closed, _ = link_camera(student)
        assert said is not None and said["code"] == "obstacles_hidden", said
        assert closed is not None and closed["code"] == 4403 and "obstacle-zone test" in closed["reason"], closed

        # A tutor and another student see everything meanwhile.
        for viewer in (tutor, other):
            status, seen = api(viewer, "GET", SCENE)
            assert status == 200 and seen == full and "obstacles_hidden" not in seen
            status, robot = api(viewer, "GET", "/api/robots/lab-1")
            assert obstacle_names({"blocks": robot["info"]["scene_boxes"], "cylinders": []}) >= {"crate", "pillar"}
            assert api(viewer, "GET", "/api/robots/lab-1/map")[0] == 200
            ws = viewer.websocket(CAMERA)
            assert camera_frame_arrives(ws)
            ws.close()
        said, closed, framed = link_camera(tutor)
        assert closed is None and framed, (said, closed)

        status, answer = api(student, "POST", f"/api/attempts/{attempt_id}/submit")
        assert status == 200, answer
    finally:
        drive.close()

    status, again = api(student, "GET", SCENE)
    assert status == 200 and again == full
    assert api(student, "GET", "/api/robots/lab-1/map")[0] == 200
    camera = student.websocket(CAMERA)
    assert camera_frame_arrives(camera)
    camera.close()


def test_the_obstacles_come_back_when_the_attempts_deadline_passes(app, client_as, course_people) -> None:
    from middleware.db import session_factory
    from middleware.models.assessment import Attempt

    student = client_as("student1")
    exam_id = zone_exam(client_as("tutor1"), course_people["course"])
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    try:
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        assert "obstacles_hidden" in api(student, "GET", SCENE)[1]
        with session_factory(app)() as session:  # the deadline passes; nobody has looked at the attempt since
            session.get(Attempt, answer["attempt"]["id"]).deadline_at = datetime.now(UTC) - timedelta(seconds=1)
            session.commit()
        # Every process reads the rule again at most RECHECK_S later (a deadline moved, as here, is seen then).
        deadline = time.monotonic() + RECHECK_S + 2.0
        while "obstacles_hidden" in (scene := api(student, "GET", SCENE)[1]):
            assert time.monotonic() < deadline, "the obstacles did not come back after the deadline"
            time.sleep(0.2)
        assert obstacle_names(scene)
        camera = student.websocket(CAMERA)
        assert camera_frame_arrives(camera)
        camera.close()
    finally:
        drive.close()


def test_the_students_practice_robot_hides_the_obstacles_too(app, live_server, client_as, course_people) -> None:
    from middleware.teaching.practice_robots import practice_manager

    student = client_as("student1")
    exam_id = zone_exam(client_as("tutor1"), course_people["course"])
    practice_manager(live_server.app).cap = 2
    status, started = api(student, "POST", "/api/practice")
    assert status == 202, started
    name = started["name"]
    drive = student.websocket("/ws/robots/lab-1/drive")
    try:
        assert receive_json(drive)["type"] == "ready"
        status, full = api(student, "GET", f"/api/robots/{name}/scene")
        assert status == 200 and obstacle_names(full), full  # the practice robot runs the lab scene
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        status, hidden = api(student, "GET", f"/api/robots/{name}/scene")
        assert status == 200 and not obstacle_names(hidden) and hidden["obstacles_hidden"]
        for path in (f"/ws/robots/{name}/camera", "/ws/practice/camera"):
            ws = student.websocket(path)
            assert first_error(ws)["code"] == "obstacles_hidden", path
            assert closed_with(ws) == 4403, path
    finally:
        drive.close()
        practice_manager(live_server.app).shutdown()
