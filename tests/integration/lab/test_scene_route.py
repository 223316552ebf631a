"""GET /api/robots/<r>/scene against a real skill server: the static world for the browser's 3D views, cached by
its version, and refused to whoever may not see the robot's camera."""

from __future__ import annotations

import json

import pytest

from tests.conftest import LabClient
from tests.integration.lab.test_robot_channels import closed_with, receive_json
from tests.integration.teaching.test_practice_console_and_uploads import _client


def get_json(client: LabClient, path: str, headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], dict]:
    accept = {"Accept": "application/json", **(headers or {})}
    status, answer_headers, body = client.request("GET", path, headers=accept)
    return status, answer_headers, json.loads(body) if body else {}


def test_a_student_gets_the_scene_and_then_only_a_304_for_the_version_held(student_client: LabClient) -> None:
    status, headers, scene = get_json(student_client, "/api/robots/lab-1/scene")
    assert status == 200 and scene["scene_name"] == "lab"
    assert headers["ETag"] == f'"{scene["version"]}"' and "no-cache" in headers["Cache-Control"]
    assert {block["name"] for block in scene["blocks"]} >= {"wall_east", "wall_west", "crate"}
    assert {mark["kind"] for mark in scene["marks"]} == {"grid", "paint"} and scene["floor"]["kind"] == "floor"
    assert scene["track"] is None
    camera = scene["camera"]
    assert (camera["width_px"], camera["height_px"], camera["hfov_deg"]) == (320, 240, 60.0)
    assert (camera["mount_forward_m"], camera["mount_height_m"]) == (0.17, 0.30)
    assert len(camera["light_direction"]) == 3 and camera["background_rgba"] == [1.0, 1.0, 1.0, 1.0]
    assert (camera["sample_offset_x_px"], camera["sample_offset_y_px"]) == (-0.5, 0.5)  # TinyRenderer: corners
    assert {part["shape"] for part in scene["robot_parts"]} == {"box", "cylinder", "sphere"}
    assert scene["laser"]["height_m"] == 0.20 and len(scene["sonar"]["sonars"]) == 16

    status, _, body = student_client.request("GET", "/api/robots/lab-1/scene",
                                             headers={"If-None-Match": headers["ETag"]})
    assert (status, body) == (304, "")
    status, _, again = get_json(student_client, "/api/robots/lab-1/scene", {"If-None-Match": '"sha256-old"'})
    assert status == 200 and again == scene


def test_an_unknown_robot_is_404_and_an_offline_one_503_with_a_sentence(student_client: LabClient) -> None:
    status, _, error = get_json(student_client, "/api/robots/nobody/scene")
    assert (status, error["error"]["code"], error["error"]["field"]) == (404, "unknown_robot", "robot_name")
    status, _, error = get_json(student_client, "/api/robots/ghost/scene")
    assert (status, error["error"]["code"]) == (503, "robot_offline")
    assert "Try again" in error["error"]["message"]


def test_someone_not_logged_in_gets_no_scene(lab_client: LabClient) -> None:
    status, _, body = lab_client.request("GET", "/api/robots/lab-1/scene", headers={"Accept": "application/json"})
    assert status == 401 and "lab" not in body


@pytest.fixture
def ann_and_bob(live_server):
    """ann's running practice robot (only ann may see it), and clients for ann and bob."""
    from middleware.teaching.practice_robots import practice_manager

    ann, bob = _client(live_server, "ann"), _client(live_server, "bob")
    practice_manager(live_server.app).cap = 2
    status, _, _ = ann.request("POST", "/api/practice", headers={
        "X-CSRFToken": ann.csrf_token("/teaching"), "Accept": "application/json"})
    assert status == 202
    try:
        yield ann, bob
    finally:
        practice_manager(live_server.app).shutdown()


def test_a_practice_robots_scene_is_its_owners_alone_as_its_camera_is(ann_and_bob) -> None:
    ann, bob = ann_and_bob
    status, _, scene = get_json(ann, "/api/robots/practice-ann/scene")
    assert status == 200 and scene["version"].startswith("sha256-")
    status, _, error = get_json(bob, "/api/robots/practice-ann/scene")
    assert (status, error["error"]["code"]) == (404, "unknown_robot")  # answered as a robot that does not exist
    camera = bob.websocket("/ws/robots/practice-ann/camera")
    assert receive_json(camera)["code"] == "unknown_robot" and closed_with(camera) == 4404
