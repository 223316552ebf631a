"""The channels' messages as described (middleware/api/channels.py, the OpenAPI document's x-websocket section)
against what the channels really send: a student opens the telemetry, localization, queue, goal, drive and chat
channels of lab-1 (the real skill server), a class's tutor and student its wall, seat and chat, and a live tour's
follower its state; every message heard is checked against its channel's schema for its `type`. A message whose type
is not described, or that lacks a described required property or has one of another type, fails the test."""

from __future__ import annotations

import json
import math
import time

from jsonschema import Draft202012Validator

from middleware.api import channels
from tests.conftest import STUDENT_PASSWORD, LabClient, make_course
from tests.integration.bookings.conftest import client_as, course_people  # noqa: F401
from tests.integration.lab.test_skills_api import api
from tests.integration.teaching.test_class_wall import _close, _login, wall_lab  # noqa: F401
from tests.integration.teaching.test_practice_console_and_uploads import _api

ROBOT = "/ws/robots/<robot_name>"


def described(rule: str) -> dict[str, Draft202012Validator]:
    """The rule's sent messages by type, each as a validator of its schema."""
    validators = {}
    for schema in channels.CHANNELS[rule]["sends"]:
        for kind in schema.get("properties", {}).get("type", {}).get("enum", []):
            assert kind not in validators, f"{rule} describes '{kind}' twice"
            validators[kind] = Draft202012Validator(schema)
    return validators


def check(rule: str, messages: list[dict]) -> set[str]:
    """Checks every message against rule's schema for its type; the types seen."""
    validators = described(rule)
    assert messages, f"nothing heard on {rule}"
    for message in messages:
        assert message.get("type") in validators, f"{rule} sent an undescribed type: {message}"
        problems = [f"{'/'.join(map(str, error.absolute_path)) or '(message)'}: {error.message}"
                    for error in validators[message["type"]].iter_errors(message)]
        assert problems == [], f"{rule} '{message['type']}' differs from its description: {problems}\n{message}"
    return {message["type"] for message in messages}


def heard(ws, count: int, within_s: float = 10.0, until: str | None = None) -> list[dict]:
    """The text messages of ws: count of them, or up to one of type until, within within_s."""
    messages: list[dict] = []
    deadline = time.monotonic() + within_s
    while len(messages) < count and time.monotonic() < deadline:
        raw = ws.receive(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(raw, str):
            messages.append(json.loads(raw))
            if until is not None and messages[-1]["type"] == until:
                break
    return messages


def test_the_robot_channels_send_what_they_describe(student_client: LabClient) -> None:
    telemetry = student_client.websocket("/ws/robots/lab-1/telemetry")
    localization = student_client.websocket("/ws/robots/lab-1/localization")
    telemetry_messages = heard(telemetry, 5)
    assert "telemetry" in check(f"{ROBOT}/telemetry", telemetry_messages)
    assert "localization" in check(f"{ROBOT}/localization", heard(localization, 3))
    queue = student_client.websocket("/ws/robots/lab-1/queue")  # opening it joins the queue
    queue_messages: list[dict] = []
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and not any(m.get("is_controller") for m in queue_messages):
        queue_messages += heard(queue, 1, max(0.01, deadline - time.monotonic()))
    assert check(f"{ROBOT}/queue", queue_messages) == {"queue"} and queue_messages[-1]["is_controller"]
    # A quarter turn from wherever the robot stands: a goal long enough to report feedback before it ends.
    status, body = api(student_client, "GET", "/api/robots/lab-1/panels")
    schema = next(p for p in body["panels"] if p.get("skill") == "orientation_control")["schema"]
    heading_name = next(p["name"] for p in schema if "heading" in p["name"] and p["type"] == "double")
    theta = [m for m in heard(telemetry, 1) if m["type"] == "telemetry"] or telemetry_messages[-1:]
    target = math.remainder(theta[-1]["odometry"]["pose"]["theta_rad"] + math.pi / 2, 2 * math.pi)
    status, body = api(student_client, "POST", "/api/robots/lab-1/skills/orientation_control/goals",
                       {"parameters": {heading_name: target}, "preempt": True})
    assert status == 202, body
    watch = student_client.websocket(f"/ws/robots/lab-1/goals/{body['goal']['goal_id']}")
    goal_messages: list[dict] = []
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not any(
            m["type"] == "goal" and m["goal"]["status"] in {"succeeded", "aborted", "canceled"} for m in goal_messages):
        goal_messages += heard(watch, 1, max(0.1, deadline - time.monotonic()))
    kinds = check(f"{ROBOT}/goals/<goal_id>", goal_messages)
    assert "goal" in kinds and kinds & {"goal_feedback", "goal_event"}, kinds
    assert any(m["type"] == "goal" and m["goal"]["feedback"] is not None for m in goal_messages), \
        "no goal state with its feedback was heard: the nested feedback went unchecked"
    drive = student_client.websocket("/ws/robots/lab-1/drive")  # the controller drives: ready, ack, pong
    drive_messages = heard_all(drive, {"ready"})
    drive.send(json.dumps({"type": "drive", "sequence": 1, "linear_mps": 0.0, "angular_radps": 0.0}))
    drive_messages += heard_all(drive, {"ack"})
    drive.send(json.dumps({"type": "ping", "id": 7}))
    drive_messages += heard_all(drive, {"pong"})
    assert {"ready", "ack", "pong"} <= check(f"{ROBOT}/drive", drive_messages)
    queue.send(json.dumps({"type": "leave"}))
    check(f"{ROBOT}/queue", heard(queue, 1))
    for ws in (telemetry, localization, queue, watch, drive):
        ws.close()


def heard_all(ws, kinds: set[str], within_s: float = 10.0) -> list[dict]:
    """The text messages of ws until one of each of kinds arrived (or within_s passed)."""
    messages: list[dict] = []
    deadline = time.monotonic() + within_s
    while not kinds <= {m["type"] for m in messages} and time.monotonic() < deadline:
        messages += heard(ws, 1, max(0.01, deadline - time.monotonic()))
    return messages


def test_the_chat_channel_sends_what_it_describes(client_as) -> None:  # noqa: F811 (the fixture imported above)
    student, tutor = client_as("student1"), client_as("tutor1")
    mine, theirs = student.websocket("/ws/robots/lab-1/chat"), tutor.websocket("/ws/robots/lab-1/chat")
    messages = heard_all(mine, {"history"})
    heard_all(theirs, {"history"})
    mine.send(json.dumps({"type": "say", "body": "kept", "line": "k-1"}))
    messages += heard_all(mine, {"sent", "message"})
    mine.send(json.dumps({"type": "say", "body": "deleted", "line": "k-2"}))
    mine.send(json.dumps({"type": "say", "body": "", "line": "k-3"}))
    messages += heard_all(mine, {"sent", "message", "error"})
    said = next(m for m in messages if m["type"] == "message" and m["message"]["body"] == "deleted")["message"]["id"]
    theirs.send(json.dumps({"type": "delete", "id": said}))
    messages += heard_all(mine, {"deleted"})
    again = student.websocket("/ws/robots/lab-1/chat")
    messages += heard_all(again, {"history"})
    kinds = check(f"{ROBOT}/chat", messages)
    assert kinds == {"history", "sent", "message", "error", "deleted"}, kinds
    assert any(m["type"] == "history" and m["messages"] for m in messages), "no history with a line was heard"
    for ws in (mine, theirs, again):
        ws.close()


def test_the_class_channels_send_what_they_describe(wall_lab) -> None:  # noqa: F811 (imported above)
    """The class wall (seats, poses), the student's seat (a hand, a tutor's pointer) and the class chat, on the class
    of tests/integration/teaching/test_class_wall.py (two students, a practice robot each)."""
    server, course_id, ids = wall_lab
    tutor, student = _login(server, "tutor1"), _login(server, "s01")
    wall, mine = tutor.websocket(f"/ws/courses/{course_id}/class-wall"), student.websocket("/ws/class-session/wall")
    room = student.websocket("/ws/class-session/chat")
    try:
        assert _api(student, "POST", "/api/class-session/hand", {"text": "Described?"})[0] == 201
        assert _api(tutor, "POST", f"/api/courses/{course_id}/class-wall/seats/{ids['s01']}",
                    {"action": "note", "text": "Look here.", "point": {"x_m": 0.5, "y_m": -0.25}})[0] == 200
        def posed(messages: list[dict]) -> bool:  # the poses once a robot's telemetry was heard: rows to check
            return any(m["type"] == "poses" and m["robots"] for m in messages)

        def handed(messages: list[dict]) -> bool:  # the first seats may be read before the hand was saved
            return any(seat["hand"] for m in messages if m["type"] == "seats" for seat in m["seats"])

        wall_messages = heard_all(wall, {"seats", "poses"}, 20)
        deadline = time.monotonic() + 20
        while not (posed(wall_messages) and handed(wall_messages)) and time.monotonic() < deadline:
            wall_messages += heard(wall, 1, 1)
        assert posed(wall_messages), "no robot's pose on the wall"
        assert check("/ws/courses/<int:course_id>/class-wall", wall_messages) >= {"seats", "poses"}
        assert handed(wall_messages), "the raised hand never reached the wall"
        seat_messages = heard(mine, 1, 10)
        deadline = time.monotonic() + 10
        while not (seat_messages[-1:] and seat_messages[-1]["hand"] and seat_messages[-1]["notices"]) \
                and time.monotonic() < deadline:
            seat_messages += heard(mine, 1, 1)
        assert check("/ws/class-session/wall", seat_messages) == {"seat"}
        assert seat_messages[-1]["hand"] and seat_messages[-1]["notices"], seat_messages[-1]
        assert check("/ws/class-session/chat", heard_all(room, {"history"})) == {"history"}
    finally:
        _close(wall, mine, room)


def test_the_live_tour_channel_sends_what_it_describes(app, student_client: LabClient) -> None:
    """A live class of the demo's first tour on lab-1, led by tutor1, followed by student1 of its course."""
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.teaching import GuidedSession, Tour
    from middleware.teaching.demo_content import DEMO_TOURS

    with session_factory(app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        session.commit()
    course_id = make_course(app, "LIVE1", {"tutor1": "tutor", "student1": "student"})
    with session_factory(app)() as session, session.begin():
        tutor_id = session.query(User).filter_by(username="tutor1").one().id
        tour = Tour(slug="live-tour", title="Live", steps_json=json.dumps(DEMO_TOURS[0]["steps"]))
        session.add(tour)
        session.flush()
        live = GuidedSession(tour_id=tour.id, robot_name="lab-1", tutor_id=tutor_id, course_id=course_id,
                             step_index=0, control_user_id=tutor_id, version=1)
        session.add(live)
        session.flush()
        live_id = live.id
    page = student_client.websocket(f"/ws/tour-sessions/{live_id}")
    messages = heard_all(page, {"state"})
    assert check("/ws/tour-sessions/<int:session_id>", messages) == {"state"}
    assert messages[-1]["step"] and messages[-1]["controller"] == "tutor1", messages[-1]
    page.close()
