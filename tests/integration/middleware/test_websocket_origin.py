"""Every WebSocket route in the app's URL map refuses a foreign Origin and lets the page's own Origin in: the
routes are read from the map, so a new channel is tested the day it is added."""

from __future__ import annotations

from contextlib import suppress

import pytest
import simple_websocket

from tests.conftest import LabClient
from tests.integration.lab.test_robot_channels import closed_with, receive_json

# A value for each variable part of a channel's address; a new one must be added here, or the test fails.
SAMPLE_VALUES = {"robot_name": "lab-1", "goal_id": "no-such-goal", "session_id": "1", "course_id": "1"}
FOREIGN_ORIGINS = ["https://evil.example", "null", "http://127.0.0.1:1"]


def websocket_paths(app) -> list[str]:
    """The address of every WebSocket route, its variables filled with SAMPLE_VALUES."""
    paths = []
    for rule in app.url_map.iter_rules():
        if not rule.websocket:
            continue
        missing = rule.arguments - SAMPLE_VALUES.keys()
        assert not missing, f"{rule.rule}: add a sample value for {sorted(missing)} to SAMPLE_VALUES"
        paths.append(rule.build({name: SAMPLE_VALUES[name] for name in rule.arguments})[1])
    return sorted(paths)


def test_the_map_holds_every_channel_we_know(app) -> None:
    assert {"/ws/robots/lab-1/drive", "/ws/robots/lab-1/chat", "/ws/robots/lab-1/queue", "/ws/practice/camera",
            "/ws/tour-sessions/1"} <= set(websocket_paths(app))


@pytest.mark.parametrize("origin", FOREIGN_ORIGINS)
def test_every_channel_refuses_a_foreign_origin(student_client: LabClient, app, origin: str) -> None:
    for path in websocket_paths(app):
        ws = student_client.websocket(path, origin=origin)
        assert receive_json(ws)["code"] == "forbidden_origin", path
        assert closed_with(ws) == 4403, path


def test_every_channel_lets_the_pages_own_origin_in(student_client: LabClient, app) -> None:
    # simple_websocket's client sends "Host: 127.0.0.1" without the port: the page's Origin for that Host.
    own_origin = student_client.base_url.rsplit(":", 1)[0]
    for path in websocket_paths(app):
        ws = student_client.websocket(path, origin=own_origin)
        first = ws.receive(timeout=5)
        assert first is not None, path
        assert "forbidden_origin" not in str(first), path
        with suppress(simple_websocket.ConnectionClosed):  # some refuse for other reasons (no practice robot)
            ws.close()
