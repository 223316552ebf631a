"""The chat over its WebSocket and HTTP: history, delivery between sockets, rate limit, moderation, bad input."""

from __future__ import annotations

import json
import time

import pytest

from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import closed_with, receive_json


def next_of(ws, kind: str, timeout_s: float = 10.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        message = receive_json(ws, timeout_s)
        if message["type"] == kind:
            return message
    raise AssertionError(f"no {kind} message")


def say(ws, body: object) -> None:
    ws.send(json.dumps({"type": "say", "body": body}))


def test_two_sockets_see_each_others_messages(client_as) -> None:
    alice, bob = client_as("student1"), client_as("student2")
    a, b = alice.websocket("/ws/robots/lab-1/chat"), bob.websocket("/ws/robots/lab-1/chat")
    assert next_of(a, "history")["messages"] == [] and next_of(b, "history")["can_moderate"] is False
    say(a, "  hello bob  ")
    assert next_of(a, "sent")["id"] > 0
    got = next_of(b, "message")["message"]
    # Another student reads initials and an account number, not the login name a guesser would need.
    assert got["body"] == "hello bob" and got["author"].startswith("S. #") and got["author_role"] == "student"
    say(b, "hi alice")
    assert next_of(a, "message")["message"]["body"] in ("hello bob", "hi alice")
    a.close()
    b.close()
    c = client_as("tutor1").websocket("/ws/robots/lab-1/chat")
    history = next_of(c, "history")
    assert [m["body"] for m in history["messages"]] == ["hello bob", "hi alice"] and history["can_moderate"]
    assert [m["author"] for m in history["messages"]] == ["student1", "student2"], "a tutor tells who is who"
    c.close()


@pytest.mark.parametrize(("message", "field"), [
    ({"type": "say", "body": ""}, "body"),
    ({"type": "say", "body": "   "}, "body"),
    ({"type": "say", "body": "x" * 501}, "body"),
    ({"type": "say", "body": 42}, "body"),
    ({"type": "say", "body": "bell\x07"}, "body"),
    ({"type": "say", "body": "two\nlines"}, "body"),
    ({"type": "say", "body": "hi", "line": ""}, "line"),
    ({"type": "say", "body": "hi", "line": 7}, "line"),
    ({"type": "say", "body": "hi", "line": "x" * 65}, "line"),
    ({"type": "say", "body": "hi", "line": "<b>"}, "line"),
    ({"type": "shout", "body": "hi"}, "type"),
    ({"type": "delete", "id": "1"}, "id"),
    ("not json", "message"),
    ([1], "message"),
])
def test_bad_input_is_refused_naming_the_field(client_as, message, field) -> None:
    client = client_as("student1")
    ws = client.websocket("/ws/robots/lab-1/chat")
    next_of(ws, "history")
    ws.send(message if isinstance(message, str) else json.dumps(message))
    error = next_of(ws, "error")
    assert error["field"] == field, error
    ws.close()
    assert api(client, "GET", "/api/robots/lab-1/chat")[1]["messages"] == []


def test_each_answer_to_a_line_names_the_key_the_browser_gave_it(client_as) -> None:
    """The console keeps a line until its answer comes, stored or refused; the key says which line it answers."""
    ws = client_as("student1").websocket("/ws/robots/lab-1/chat")
    next_of(ws, "history")
    for n in range(6):
        ws.send(json.dumps({"type": "say", "body": f"line {n}", "line": f"k-{n}"}))
    answers = [next_of(ws, "sent") for _ in range(5)]
    assert [answer["line"] for answer in answers] == [f"k-{n}" for n in range(5)]
    refused = next_of(ws, "error")
    assert refused["code"] == "rate_limited" and refused["line"] == "k-5"
    ws.send(json.dumps({"type": "say", "body": "", "line": "k-empty"}))
    assert next_of(ws, "error")["line"] == "k-empty"
    ws.close()


def test_the_rate_limit_holds_five_messages_per_ten_seconds(client_as) -> None:
    client = client_as("student1")
    for n in range(5):
        assert api(client, "POST", "/api/robots/lab-1/chat", {"body": f"m{n}"})[0] == 201
    status, body = api(client, "POST", "/api/robots/lab-1/chat", {"body": "one too many"})
    assert status == 429 and body["error"]["code"] == "rate_limited" and body["error"]["field"] == "body"
    assert api(client_as("student2"), "POST", "/api/robots/lab-1/chat", {"body": "others still talk"})[0] == 201
    assert len(api(client, "GET", "/api/robots/lab-1/chat")[1]["messages"]) == 6


def test_a_tutor_deletes_a_message_and_it_disappears_for_everyone(client_as) -> None:
    student, tutor = client_as("student1"), client_as("tutor1")
    watcher = client_as("student2").websocket("/ws/robots/lab-1/chat")
    next_of(watcher, "history")
    message_id = api(student, "POST", "/api/robots/lab-1/chat", {"body": "rude words"})[1]["message"]["id"]
    assert next_of(watcher, "message")["message"]["id"] == message_id
    ws = tutor.websocket("/ws/robots/lab-1/chat")
    next_of(ws, "history")
    ws.send(json.dumps({"type": "delete", "id": message_id}))
    assert next_of(watcher, "deleted")["id"] == message_id
    assert api(student, "GET", "/api/robots/lab-1/chat")[1]["messages"] == []
    ws.close()
    watcher.close()


def test_a_student_cannot_delete(client_as) -> None:
    student = client_as("student1")
    message_id = api(student, "POST", "/api/robots/lab-1/chat", {"body": "mine"})[1]["message"]["id"]
    ws = client_as("student2").websocket("/ws/robots/lab-1/chat")
    next_of(ws, "history")
    ws.send(json.dumps({"type": "delete", "id": message_id}))
    assert next_of(ws, "error")["code"] == "forbidden"
    ws.close()
    status, _ = api(student, "DELETE", f"/api/robots/lab-1/chat/{message_id}")
    assert status == 403
    assert [m["id"] for m in api(student, "GET", "/api/robots/lab-1/chat")[1]["messages"]] == [message_id]


def test_after_id_returns_only_newer_messages(client_as) -> None:
    client = client_as("student1")
    first = api(client, "POST", "/api/robots/lab-1/chat", {"body": "one"})[1]["message"]["id"]
    api(client, "POST", "/api/robots/lab-1/chat", {"body": "two"})
    assert [m["body"] for m in api(client, "GET", f"/api/robots/lab-1/chat?after_id={first}")[1]["messages"]] == ["two"]
    assert api(client, "GET", "/api/robots/lab-1/chat?after_id=x")[0] == 400


def test_the_chat_socket_makes_the_channel_checks(client_as) -> None:
    ws = client_as(None).websocket("/ws/robots/lab-1/chat")
    assert receive_json(ws)["code"] == "not_logged_in" and closed_with(ws) == 4401
    ws = client_as("student1").websocket("/ws/robots/nope/chat")
    error = receive_json(ws)
    assert error["code"] == "unknown_robot" and error["field"] == "robot_name" and closed_with(ws) == 4404
    ws = client_as("student1").websocket("/ws/robots/lab-1/chat", origin="https://evil.example")
    assert receive_json(ws)["code"] == "forbidden_origin" and closed_with(ws) == 4403
