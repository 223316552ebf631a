"""One WebSocket per page: /ws/link carries the robot channels a console needs, each opened with its own checks
and closed with its own code, against a real skill server."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator

import pytest

from middleware.robots.messages import unpack_camera_frame
from tests.conftest import LabClient


def _next(ws, timeout_s: float = 5.0) -> tuple[int, str | bytes]:
    """(channel number, message) of the link's next message."""
    message = ws.receive(timeout=timeout_s)
    assert message is not None, "nothing arrived on the link"
    if isinstance(message, bytes):
        return int.from_bytes(message[:4], "big"), message[4:]
    head, _, text = message.partition(" ")
    return int(head), text


_unmatched: dict[int, list[tuple[int, str | bytes]]] = {}


@pytest.fixture(autouse=True)
def _forget_unmatched() -> Iterator[None]:
    yield
    _unmatched.clear()  # a later test's socket may reuse an id


def _until(ws, predicate, timeout_s: float = 10.0):
    """The link's first message that predicate accepts, earlier unmatched ones first: the channels interleave in any
    order (a drive's "ready" may come before the camera's first frame), so what one wait skips, a later one reads."""
    kept = _unmatched.setdefault(id(ws), [])
    for index, (sub, message) in enumerate(kept):
        if predicate(sub, message):
            del kept[index]
            return sub, message
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        sub, message = _next(ws, max(0.05, deadline - time.monotonic()))
        if predicate(sub, message):
            return sub, message
        kept.append((sub, message))
    raise AssertionError("the expected message never came")


def _control(message) -> dict:
    return json.loads(message) if isinstance(message, str) else {}


def test_a_page_subscribes_to_camera_telemetry_and_drive_on_one_socket(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/link")
    for sub, channel in ((1, "camera"), (2, "telemetry"), (3, "drive")):
        ws.send(json.dumps({"type": "subscribe", "sub": sub, "path": f"/ws/robots/lab-1/{channel}"}))
    _until(ws, lambda sub, m: sub == 1 and isinstance(m, bytes) and unpack_camera_frame(m)[0]["frame_sequence"] > 0)
    _until(ws, lambda sub, m: sub == 2 and json.loads(m)["type"] == "telemetry")
    _, ready = _until(ws, lambda sub, m: sub == 3 and json.loads(m)["type"] == "ready")
    assert json.loads(ready)["max_linear_mps"] > 0
    ws.send("3 " + json.dumps({"type": "drive", "sequence": 1, "linear_mps": 0.1, "angular_radps": 0.0}))
    _, ack = _until(ws, lambda sub, m: sub == 3 and json.loads(m)["type"] in {"ack", "error"})
    assert json.loads(ack)["type"] == "ack", ack
    ws.send(json.dumps({"type": "unsubscribe", "sub": 1}))
    _until(ws, lambda sub, m: sub == 0 and _control(m).get("type") == "closed" and _control(m)["sub"] == 1)


def test_each_channel_is_refused_with_its_own_code_and_the_link_stays_open(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/link")
    ws.send(json.dumps({"type": "subscribe", "sub": 5, "path": "/ws/robots/no-such-robot/camera"}))
    _, closed = _until(ws, lambda sub, m: sub == 0 and _control(m).get("type") == "closed")
    assert _control(closed)["code"] == 4404 and _control(closed)["sub"] == 5
    ws.send(json.dumps({"type": "subscribe", "sub": 6, "path": "/ws/nowhere"}))
    _, closed = _until(ws, lambda sub, m: sub == 0 and _control(m).get("type") == "closed")
    assert _control(closed)["code"] == 4404
    ws.send(json.dumps({"type": "subscribe", "sub": 7, "path": "/ws/link"}))
    _, closed = _until(ws, lambda sub, m: sub == 0 and _control(m).get("type") == "closed")
    assert _control(closed)["code"] == 4404  # a link inside a link is no channel
    for hostile, field in (("{]", "message"), (json.dumps({"type": "subscribe", "sub": -1, "path": "/ws/x"}), "sub"),
                           (json.dumps({"type": "subscribe", "sub": 8, "path": 42}), "path")):
        ws.send(hostile)
        _, error = _until(ws, lambda sub, m: sub == 0 and _control(m).get("type") == "error")
        assert _control(error)["field"] == field
    ws.send(json.dumps({"type": "subscribe", "sub": 9, "path": "/ws/robots/lab-1/telemetry"}))
    _until(ws, lambda sub, m: sub == 9 and json.loads(m)["type"] == "telemetry")
