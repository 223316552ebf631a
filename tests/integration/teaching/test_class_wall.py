"""The class wall over HTTP and its sockets, with real robots, on SQLite and on PostgreSQL: a student never reaches the
wall nor another student's robot; a raised hand reaches the wall at once and comes down when answered; a takeover
refuses the student until the tutor gives the robot back or leaves; the wall carries every robot's pose on one socket
and stop-all stops them."""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Iterator

import pytest
import simple_websocket

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, add_test_account, make_course, make_test_app
from tests.integration.lab.test_robot_channels import closed_with, receive_json
from tests.integration.teaching.test_practice_console_and_uploads import _api

STUDENTS = ["s01", "s02"]


@pytest.fixture(scope="module")
def wall_lab(module_database_url: str, tmp_path_factory: pytest.TempPathFactory,
             skill_server_address: str) -> Iterator[tuple[LiveServer, int, dict[str, int]]]:
    """tutor1 teaching a course of two students whose class session runs (a robot each), tutor2 teaching another
    course, and s03 a student of that other course."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager
    from tests.conftest import _let_go

    app = make_test_app(module_database_url, f"lab-1={skill_server_address}", tmp_path_factory.mktemp("wall"))
    with session_factory(app)() as session:
        for name in ["tutor1", "tutor2"]:
            add_test_account(session, name, "tutor")
        for name in [*STUDENTS, "s03"]:
            add_test_account(session, name, "student")
        session.commit()
        ids = {user.username: user.id for user in session.query(User)}
    course_id = make_course(app, "ROB101", {"tutor1": "tutor", **dict.fromkeys(STUDENTS, "student")})
    make_course(app, "ROB202", {"tutor2": "tutor", "s03": "student"})
    server = LiveServer(app)
    try:
        tutor = _login(server, "tutor1")
        status, opened = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
        assert status == 201, opened
        deadline = time.monotonic() + 90
        while _api(tutor, "GET", f"/api/courses/{course_id}/class-session")[1]["counts"]["ready"] < len(STUDENTS):
            assert time.monotonic() < deadline, "the class's robots did not start"
            time.sleep(0.3)
        yield server, course_id, ids
    finally:
        practice_manager(app).shutdown()
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()


def _login(server: LiveServer, name: str) -> LabClient:
    client = LabClient(server.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def _until(ws, wanted, timeout_s: float = 10.0) -> dict:
    """The first message of ws for which wanted(message) holds."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        message = receive_json(ws, max(0.05, deadline - time.monotonic()))
        if wanted(message):
            return message
    raise AssertionError("the awaited message never came")


def _close(*sockets) -> None:
    for ws in sockets:
        with contextlib.suppress(simple_websocket.ConnectionClosed):
            ws.close()


def _seat(message: dict, username: str) -> dict:
    return next(seat for seat in message["seats"] if seat["username"] == username)


def _drive(client: LabClient) -> tuple[int, dict]:
    return _api(client, "POST", "/api/practice/commands", {"command": {"drive": {"linear_mps": 0.15,
                                                                                 "angular_radps": 0.4}}})


def test_a_student_never_reaches_the_wall_nor_another_students_robot(wall_lab) -> None:
    server, course_id, ids = wall_lab
    student, outsider, other_tutor = _login(server, "s01"), _login(server, "s03"), _login(server, "tutor2")
    wall = f"/api/courses/{course_id}/class-wall"
    for client in (student, outsider, other_tutor):
        assert client.request("GET", f"/courses/{course_id}/class/wall")[0] == 403
        assert _api(client, "GET", wall)[0] == 403
        assert _api(client, "POST", wall, {"action": "stop_all"})[0] == 403
        assert _api(client, "POST", f"{wall}/seats/{ids['s02']}", {"action": "take_over"})[0] == 403
        ws = client.websocket(f"/ws/courses/{course_id}/class-wall")
        assert receive_json(ws)["code"] == "forbidden" and closed_with(ws) == 4403
    for client in (student, outsider, other_tutor):  # another student's robot is a robot that does not exist
        assert client.request("GET", "/lab/practice-s02")[0] == 404
        assert _api(client, "GET", "/api/robots/practice-s02")[0] == 404
        ws = client.websocket("/ws/robots/practice-s02/telemetry")
        assert receive_json(ws)["code"] == "unknown_robot" and closed_with(ws) == 4404
    # The class's own tutor watches it: its console and its streams, read-only.
    tutor = _login(server, "tutor1")
    assert tutor.request("GET", "/lab/practice-s02")[0] == 200
    ws = tutor.websocket("/ws/robots/practice-s02/telemetry")
    assert _until(ws, lambda message: message.get("type") == "telemetry")["odometry"]
    ws.close()
    assert _api(tutor, "POST", "/api/robots/practice-s02/skills/go_to_goal/goals",
                {"parameters": {"goal_x_m": 0.3, "goal_y_m": 0.0}})[1]["error"]["code"] == "not_controller"
    # Hostile bodies name their field.
    for body, field in [({}, "action"), ({"action": "fly"}, "action"), ({"action": "note", "text": 5}, "text"),
                        ({"action": "note", "point": {"x_m": "1", "y_m": 0}}, "point.x_m"),
                        ({"action": "note", "text": "x" * 301}, "text")]:
        status, answer = _api(tutor, "POST", f"{wall}/seats/{ids['s01']}", body)
        assert (status, answer["error"]["field"]) == (400, field), body
    assert _api(tutor, "POST", f"{wall}/seats/{ids['s03']}", {"action": "stop"})[1]["error"]["field"] == "user_id"
    status, answer = _api(tutor, "POST", wall, {"action": "push", "kind": "test", "id": 2**40})
    assert (status, answer["error"]["field"]) == (400, "id")


def test_a_raised_hand_reaches_the_wall_at_once_and_comes_down_when_answered(wall_lab) -> None:
    server, course_id, ids = wall_lab
    tutor, student = _login(server, "tutor1"), _login(server, "s01")
    wall = tutor.websocket(f"/ws/courses/{course_id}/class-wall")
    mine = student.websocket("/ws/class-session/wall")
    try:
        first = _until(wall, lambda message: message["type"] == "seats")
        assert _seat(first, "s01")["hand"] is None and _seat(first, "s01")["seat_state"] == "ready"
        assert _until(mine, lambda message: message["type"] == "seat")["hand"] is None
        raised_at = time.monotonic()
        status, answer = _api(student, "POST", "/api/class-session/hand", {"text": "  My robot   turns left? "})
        assert status == 201 and answer["hand"]["text"] == "My robot turns left?"
        seats = _until(wall, lambda message: message["type"] == "seats" and _seat(message, "s01")["hand"])
        # Announced, not found by the wall's periodic read (every 2 s).
        assert time.monotonic() - raised_at < 1.9
        assert _seat(seats, "s01")["hand"]["text"] == "My robot turns left?"
        assert _api(tutor, "POST", f"/api/courses/{course_id}/class-wall/seats/{ids['s01']}",
                    {"action": "answer"})[0] == 200
        _until(wall, lambda message: message["type"] == "seats" and _seat(message, "s01")["hand"] is None)
        _until(mine, lambda message: message["type"] == "seat" and message["hand"] is None)
        status, answer = _api(tutor, "POST", f"/api/courses/{course_id}/class-wall/seats/{ids['s01']}",
                              {"action": "note", "text": "Look at the sonar.", "point": {"x_m": 0.5, "y_m": -0.25}})
        assert status == 200
        notice = _until(mine, lambda message: message["type"] == "seat" and message["notices"])["notices"][0]
        assert (notice["kind"], notice["text"], notice["x_m"], notice["from"]) == ("pointer", "Look at the sonar.",
                                                                                   0.5, "tutor1")
        # A push reaches every student: a test of the course, with its link.
        from middleware.db import session_factory
        from middleware.models.assessment import Exam

        with session_factory(server.app)() as session:
            exam = Exam(course_id=course_id, title="Quiz on sonar", kind="quiz")
            session.add(exam)
            session.commit()
            exam_id = exam.id
        status, pushed = _api(tutor, "POST", f"/api/courses/{course_id}/class-wall",
                              {"action": "push", "kind": "test", "id": exam_id})
        assert status == 200 and pushed["url"] == f"/assessment/exams/{exam_id}", pushed
        notice = _until(mine, lambda message: message["type"] == "seat" and message["notices"][0]["kind"] == "push")
        assert notice["notices"][0]["title"] == "Quiz on sonar"
        classmate = _api(_login(server, "s02"), "GET", "/api/class-session/wall")[1]
        assert classmate["notices"][0]["title"] == "Quiz on sonar"
    finally:
        _close(wall, mine)


def test_the_class_chat_is_the_chats_own_room_for_the_class_alone(wall_lab) -> None:
    server, course_id, _ids = wall_lab
    tutor, student, classmate = _login(server, "tutor1"), _login(server, "s01"), _login(server, "s02")
    rooms = [tutor.websocket(f"/ws/courses/{course_id}/class-wall/chat"), student.websocket("/ws/class-session/chat"),
             classmate.websocket("/ws/class-session/chat")]
    try:
        for ws in rooms:
            assert _until(ws, lambda message: message["type"] == "history")["robot_name"].startswith("class:")
        rooms[1].send(json.dumps({"type": "say", "body": "Is the sonar noisy?", "line": "k1"}))
        for ws in rooms:
            said = _until(ws, lambda message: message["type"] == "message")["message"]
            assert said["body"] == "Is the sonar noisy?"
        for client, path in [(_login(server, "s03"), "/ws/class-session/chat"),
                             (_login(server, "tutor2"), f"/ws/courses/{course_id}/class-wall/chat")]:
            ws = client.websocket(path)
            assert receive_json(ws)["code"] in ("no_class_session", "forbidden") and closed_with(ws) in (4403, 4404)
        # The class's room is no robot's: the robots' chat API does not reach it.
        assert _api(student, "GET", f"/api/robots/{said['robot_name']}/chat")[0] == 404
    finally:
        _close(*rooms)


def test_a_takeover_refuses_the_student_until_given_back_or_the_tutor_leaves(wall_lab) -> None:
    from middleware.access.commands import robot_commands

    server, course_id, ids = wall_lab
    tutor, student = _login(server, "tutor1"), _login(server, "s02")
    seat_url = f"/api/courses/{course_id}/class-wall/seats/{ids['s02']}"
    wall = tutor.websocket(f"/ws/courses/{course_id}/class-wall")
    mine = student.websocket("/ws/class-session/wall")
    try:
        _until(wall, lambda message: message["type"] == "seats")
        assert _drive(student)[0] == 202
        status, answer = _api(tutor, "POST", seat_url, {"action": "take_over"})
        assert status == 200 and answer["watch_url"] == "/lab/practice-s02"
        assert _until(mine, lambda message: message["type"] == "seat" and message["held_by"])["held_by"] == "tutor1"
        status, refused = _drive(student)
        assert (status, refused["error"]["code"]) == (403, "not_controller"), refused
        # The tutor drives it now, through the command path, as its controller.
        tutor_commands = robot_commands(server.app).for_user("practice-s02", ids["tutor1"])
        assert tutor_commands.is_controller()
        tutor_commands.drive(tutor_commands.link.next_sequence(), 0.1, 0.0)
        assert _api(tutor, "POST", seat_url, {"action": "give_back"})[0] == 200
        _until(mine, lambda message: message["type"] == "seat" and message["held_by"] is None)
        assert _drive(student)[0] == 202
        assert not robot_commands(server.app).for_user("practice-s02", ids["tutor1"]).is_controller()

        assert _api(tutor, "POST", seat_url, {"action": "take_over"})[0] == 200
        _until(mine, lambda message: message["type"] == "seat" and message["held_by"])
        wall.close()  # the tutor leaves: the robot goes back to its student by itself
        _until(mine, lambda message: message["type"] == "seat" and message["held_by"] is None)
        assert _drive(student)[0] == 202
    finally:
        _close(wall, mine)


def test_the_wall_carries_every_robot_on_one_socket_and_stop_all_stops_them(wall_lab) -> None:
    server, course_id, ids = wall_lab
    tutor = _login(server, "tutor1")
    students = [_login(server, name) for name in STUDENTS]
    wall = tutor.websocket(f"/ws/courses/{course_id}/class-wall")
    try:
        for student in students:
            assert _drive(student)[0] == 202

        def all_driving(message: dict) -> bool:
            rows = message.get("robots") or []
            return message["type"] == "poses" and len(rows) == 2 and all(row[7] == "driving" for row in rows)

        poses = _until(wall, all_driving, 20)
        assert {row[0] for row in poses["robots"]} == {ids[name] for name in STUDENTS}
        assert all(0 <= row[6] <= 1 for row in poses["robots"])  # the battery's charge
        status, answer = _api(tutor, "POST", f"/api/courses/{course_id}/class-wall", {"action": "stop_all"})
        assert status == 200 and answer == {"action": "stop_all", "done": 2, "refused": {}}, answer
        stopped_at = time.monotonic()
        _until(wall, lambda message: message["type"] == "poses" and len(message["robots"]) == 2
               and all(row[7] == "idle" for row in message["robots"]), 10)
        assert time.monotonic() - stopped_at < 5
        # A skill's run shows as the skill (asked of the robot beside the poses).
        status, goal = _api(students[0], "POST", "/api/robots/practice-s01/skills/go_to_goal/goals",
                            {"parameters": {"goal_x_m": 0.6, "goal_y_m": 0.4}})
        assert status == 202, goal
        _until(wall, lambda message: message["type"] == "poses" and any(
            row[0] == ids["s01"] and row[7] == "skill:go_to_goal" for row in message["robots"]), 15)
        status, answer = _api(tutor, "POST", f"/api/courses/{course_id}/class-wall", {"action": "dock_all"})
        assert status == 200 and answer["done"] == 2, answer
        wall.send(json.dumps({"type": "anything"}))  # what the page sends is dropped; the socket stays open
        assert _until(wall, lambda message: message["type"] == "poses")
    finally:
        _close(wall)
