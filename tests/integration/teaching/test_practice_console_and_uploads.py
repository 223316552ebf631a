"""A practice robot in the full lab console, for its owner only; and lesson video uploads (tutors only)."""

from __future__ import annotations

import json
import secrets
import time
from http.client import HTTPConnection
from pathlib import Path
from urllib.parse import urlsplit
from urllib.request import Request

import pytest

from tests.conftest import LabClient
from tests.integration.lab.test_robot_channels import closed_with, receive_json

PASSWORD = "correct-horse-battery"
CHANNELS = ("camera", "telemetry", "drive", "queue", "chat", "localization", "goals/g-1")


def _user(app, username: str, role: str = "student") -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(app)() as session:
        create_user(session, username, role, PASSWORD)
        session.commit()


def _client(live_server, username: str, role: str = "student") -> LabClient:
    _user(live_server.app, username, role)
    client = LabClient(live_server.url)
    assert client.login(username, PASSWORD) == 302
    return client


def _api(client: LabClient, method: str, path: str, body: object | None = None) -> tuple[int, dict]:
    token = client.csrf_token("/teaching")
    data = None if body is None else json.dumps(body).encode()
    request = Request(client.base_url + path, data=data, method=method,
                      headers={"Content-Type": "application/json", "X-CSRFToken": token, "Accept": "application/json"})
    try:
        with client._opener.open(request, timeout=20) as response:
            return response.status, json.loads(response.read())
    except Exception as error:  # noqa: BLE001 - 4xx/5xx are answers here
        return error.code, json.loads(error.read())


def refusal(client: LabClient, path: str) -> tuple[str, int]:
    """The error code and close code a channel refuses with."""
    ws = client.websocket(path)
    return receive_json(ws)["code"], closed_with(ws)


@pytest.fixture
def practice(live_server):
    """ann's running practice robot, and two clients: ann (its owner) and bob."""
    from middleware.teaching.practice_robots import practice_manager

    ann, bob = _client(live_server, "ann"), _client(live_server, "bob")
    practice_manager(live_server.app).cap = 2
    status, started = _api(ann, "POST", "/api/practice")
    assert status == 202 and started["name"] == "practice-ann" and started["starting"]
    assert _api(ann, "GET", "/api/practice")[1]["console_url"] == "/lab/practice-ann"  # started after the commit
    try:
        yield ann, bob
    finally:
        practice_manager(live_server.app).shutdown()


def test_the_owner_has_the_full_console_and_everyone_else_gets_404s(live_server, practice) -> None:
    ann, bob = practice
    status, _, page = ann.request("GET", "/lab/practice-ann")
    assert status == 200 and 'data-robot="practice-ann"' in page
    status, panels = _api(ann, "GET", "/api/robots/practice-ann/panels")
    assert status == 200 and panels["personal"] and panels["skills_available"]
    kinds = {p["kind"] for p in panels["panels"]}
    assert {"camera", "map", "odometry", "sonar", "laser", "drive", "skill", "response-times", "queue"} <= kinds
    status, description = _api(ann, "GET", "/api/robots/practice-ann")
    assert status == 200 and description["online"] and description["title"] == "Practice robot of ann"
    assert "practice-ann" not in ann.request("GET", "/lab")[2]  # never listed among the lab robots

    assert bob.request("GET", "/lab/practice-ann")[0] == 404
    for method, path, body in [
        ("GET", "/api/robots/practice-ann", None),
        ("GET", "/api/robots/practice-ann/panels", None),
        ("GET", "/api/robots/practice-ann/map", None),
        ("GET", "/api/robots/practice-ann/goals/g-1", None),
        ("DELETE", "/api/robots/practice-ann/goals/g-1", None),
        ("POST", "/api/robots/practice-ann/skills/go_to_goal/goals", {"parameters": {"goal_x_m": 0.5}}),
        ("GET", "/api/robots/practice-ann/chat", None),
    ]:
        status, error = _api(bob, method, path, body)
        assert (status, error["error"]["code"]) == (404, "unknown_robot"), (method, path)
    for channel in CHANNELS:
        assert refusal(bob, f"/ws/robots/practice-ann/{channel}") == ("unknown_robot", 4404), channel
    anonymous = LabClient(live_server.url)
    assert anonymous.request("GET", "/lab/practice-ann")[0] == 302  # to the login page
    assert refusal(anonymous, "/ws/robots/practice-ann/camera") == ("not_logged_in", 4401)


def test_the_owner_commands_their_robot_from_every_source_in_or_out_of_its_queue(live_server, practice) -> None:
    ann, _bob = practice
    # The owner is the practice robot's only controller: the skill panel works before the console's queue.
    status, activated = _api(ann, "POST", "/api/robots/practice-ann/skills/go_to_goal/goals",
                             {"parameters": {"goal_x_m": 0.3, "goal_y_m": 0.0}})
    assert status == 202, activated
    queue = ann.websocket("/ws/robots/practice-ann/queue")
    deadline = time.monotonic() + 10
    seat = receive_json(queue)
    while not seat.get("is_controller") and time.monotonic() < deadline:
        seat = receive_json(queue)
    assert seat["is_controller"] and seat["controller"] == "ann" and seat["queue_size"] == 1
    status, activated = _api(ann, "POST", "/api/robots/practice-ann/skills/go_to_goal/goals",
                             {"parameters": {"goal_x_m": 0.3, "goal_y_m": 0.0}, "preempt": True})
    assert status == 202, activated
    # The skill panel, the pad and the practice commands (lessons, tours) all go under the owner's token.
    status, stopped = _api(ann, "POST", "/api/practice/commands", {"command": {"stop": True}})
    assert status == 202 and stopped["robot"] == "practice-ann"
    queue.send(json.dumps({"type": "leave"}))
    status, stopped = _api(ann, "POST", "/api/practice/commands", {"command": {"stop": True}})
    assert status == 202  # leaving the queue does not take the robot from its owner
    queue.close()
    ws = ann.websocket("/ws/robots/practice-ann/camera")
    deadline = time.monotonic() + 10
    frame = None
    while frame is None and time.monotonic() < deadline:
        message = ws.receive(timeout=1)
        frame = message if isinstance(message, bytes) else None
    assert frame is not None, "no camera frame from the practice robot"
    ws.close()


def test_practice_names_are_unique_short_and_never_a_username() -> None:
    from middleware.teaching.practice_robots import practice_name

    assert practice_name("ann", 7) == "practice-ann"
    assert practice_name("a.b", 7) == practice_name("x" * 40, 7) == "practice-_7"
    assert len(practice_name("a" * 23, 1)) == 32


# --- lesson video uploads -------------------------------------------------------------------------------

WEBM_HEAD = b"\x1a\x45\xdf\xa3\x9f\x42\x86\x81\x01"
MP4_HEAD = b"\x00\x00\x00\x18ftypisom\x00\x00\x02\x00"


def _upload(client: LabClient, filename: str, content: bytes, path: str = "/api/lessons/videos",
            csrf: bool = True, extra_headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], bytes]:
    """A multipart POST of one "video" file (and the CSRF token as a form field, as the editor sends it)."""
    boundary = "----telelab" + secrets.token_hex(8)
    parts = []
    if csrf:
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="csrf_token"\r\n\r\n'
                     f'{client.csrf_token("/teaching")}\r\n'.encode())
    parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="video"; filename="{filename}"\r\n'
                 f"Content-Type: application/octet-stream\r\n\r\n".encode() + content + b"\r\n")
    body = b"".join(parts) + f"--{boundary}--\r\n".encode()
    headers = {"Content-Type": f"multipart/form-data; boundary={boundary}", "Accept": "application/json",
               **(extra_headers or {})}
    request = Request(client.base_url + path, data=body, method="POST", headers=headers)
    try:
        with client._opener.open(request, timeout=30) as response:
            return response.status, dict(response.headers), response.read()
    except Exception as error:  # noqa: BLE001 - 4xx/5xx are answers here
        return error.code, dict(error.headers), error.read()


def _videos(live_server) -> list[str]:
    folder = Path(live_server.app.instance_path) / "lessons"
    return sorted(p.name for p in folder.iterdir()) if folder.is_dir() else []


def test_a_tutor_uploads_webm_and_mp4_under_generated_names(live_server) -> None:
    tutor = _client(live_server, "tutor2", "tutor")
    big = WEBM_HEAD + bytes(3 * 1024 * 1024)  # above the app's 2 MB limit for other requests
    status, _, body = _upload(tutor, "../../etc/Evil Clip.webm", big)
    assert status == 201, body
    name = json.loads(body)["video_name"]
    assert name.startswith("upload-") and name.endswith(".webm") and "evil" not in name.lower()
    stored = Path(live_server.app.instance_path) / "lessons" / name
    assert stored.read_bytes() == big
    status, _, body = _upload(tutor, "clip.MP4", MP4_HEAD + b"rest")
    assert status == 201 and json.loads(body)["video_name"].endswith(".mp4")
    assert len(_videos(live_server)) == 2  # nothing else, no partial files
    status, _, page = tutor.request("GET", "/lessons/new")
    assert name in page

    status, headers, _ = _upload(tutor, "clip.webm", WEBM_HEAD + b"x", path="/lessons/videos")
    assert status == 303 and "/lessons/new?video=upload-" in headers["Location"]
    chosen = headers["Location"].split("video=")[1]
    status, _, page = tutor.request("GET", f"/lessons/new?video={chosen}")
    assert f'value="{chosen}" selected' in page and "Uploaded as" in page


@pytest.mark.parametrize(("filename", "content", "code"), [
    ("clip.webm", MP4_HEAD + b"rest", "invalid_video_content"),
    ("clip.mp4", WEBM_HEAD + b"rest", "invalid_video_content"),
    ("clip.mp4", b"<html><script>alert(1)</script>", "invalid_video_content"),
    ("clip.avi", WEBM_HEAD + b"rest", "invalid_video_type"),
    ("clip.webm.html", WEBM_HEAD + b"rest", "invalid_video_type"),
    ("clip", WEBM_HEAD + b"rest", "invalid_video_type"),
    ("clip.webm", b"", "empty_video"),
])
def test_wrong_types_and_contents_are_refused_naming_the_field(live_server, filename: str, content: bytes,
                                                               code: str) -> None:
    tutor = _client(live_server, "tutor3", "tutor")
    status, _, body = _upload(tutor, filename, content)
    error = json.loads(body)["error"]
    assert (status, error["code"], error["field"]) == (400, code, "video")
    assert "video" in error["message"]
    assert _videos(live_server) == []


def test_too_large_videos_are_refused_while_read_and_before(live_server) -> None:
    tutor = _client(live_server, "tutor4", "tutor")
    live_server.app.config["LESSON_VIDEO_MAX_BYTES"] = 100_000
    status, _, body = _upload(tutor, "clip.webm", WEBM_HEAD + bytes(150_000))  # within the body allowance
    error = json.loads(body)["error"]
    assert (status, error["code"], error["field"]) == (413, "video_too_large", "video")
    # A declared length far above the limit is refused before any of the body is read.
    url = urlsplit(tutor.base_url)
    connection = HTTPConnection(url.hostname, url.port, timeout=10)
    connection.putrequest("POST", "/api/lessons/videos")
    for header, value in {"Cookie": tutor.cookie_header(), "Content-Length": str(500 * 1024 * 1024),
                          "Content-Type": "multipart/form-data; boundary=x", "Accept": "application/json"}.items():
        connection.putheader(header, value)
    connection.endheaders()
    response = connection.getresponse()
    assert response.status == 413 and json.loads(response.read())["error"]["field"] == "video"
    connection.close()
    assert _videos(live_server) == []


def test_students_and_forged_forms_cannot_upload(live_server, student_client) -> None:
    status, _, body = _upload(student_client, "clip.webm", WEBM_HEAD + b"rest")
    assert status == 403 and json.loads(body)["error"]["code"] == "not_tutor"
    tutor = _client(live_server, "tutor5", "tutor")
    status, _, body = _upload(tutor, "clip.webm", WEBM_HEAD + b"rest", csrf=False)
    assert status == 400 and json.loads(body)["error"]["code"] == "csrf_failed"
    assert _videos(live_server) == []


def _lesson_with_video(app, video_name: str) -> None:
    from middleware.db import session_factory
    from middleware.models.teaching import Lesson

    with session_factory(app)() as session:
        session.add(Lesson(slug="plays-it", title="Plays it", summary="", video_name=video_name, cues_vtt="WEBVTT\n"))
        session.commit()


def test_a_tutor_deletes_a_video_no_lesson_plays_but_never_one_a_lesson_plays(
    live_server, student_client
) -> None:
    tutor = _client(live_server, "tutor6", "tutor")
    kept = json.loads(_upload(tutor, "kept.webm", WEBM_HEAD + b"kept")[2])["video_name"]
    spare = json.loads(_upload(tutor, "spare.webm", WEBM_HEAD + b"spare")[2])["video_name"]
    other = json.loads(_upload(tutor, "other.mp4", MP4_HEAD + b"other")[2])["video_name"]
    _lesson_with_video(live_server.app, kept)
    _, _, page = tutor.request("GET", "/lessons/new")
    assert f"/lessons/videos/{spare}/delete" in page and f"/lessons/videos/{kept}/delete" not in page

    # Refusals change nothing and name the field.
    assert _api(student_client, "DELETE", f"/api/lessons/videos/{spare}")[0] == 403
    status, body = _api(tutor, "DELETE", f"/api/lessons/videos/{kept}")
    assert (status, body["error"]["code"], body["error"]["field"]) == (409, "video_in_use", "video_name")
    assert "Plays it" in body["error"]["message"]
    assert _api(tutor, "DELETE", "/api/lessons/videos/..%2Fapp.sqlite3")[0] == 404  # no route takes a slash
    for name in ("..", "app.sqlite3", "missing.webm", "UPPER.webm", ".hidden.webm.part"):
        status, body = _api(tutor, "DELETE", f"/api/lessons/videos/{name}")
        assert (status, body["error"]["code"]) == (404, "unknown_video"), name
    assert _videos(live_server) == sorted([kept, spare, other])

    status, body = _api(tutor, "DELETE", f"/api/lessons/videos/{spare}")
    assert status == 200 and body["deleted"] == spare and spare not in body["videos"]
    # The editor's button: back to the editor with a message; a refusal is a message too.
    token = tutor.csrf_token("/lessons/new")
    status, headers, _ = tutor.request("POST", f"/lessons/videos/{other}/delete", {"csrf_token": token})
    assert status == 303 and headers["Location"].endswith("/lessons/new")
    status, headers, _ = tutor.request("POST", f"/lessons/videos/{kept}/delete", {"csrf_token": token})
    assert status == 303
    _, _, page = tutor.request("GET", "/lessons/new")
    assert "give that lesson another video first" in page and "unused-videos" not in page
    assert tutor.request("POST", f"/lessons/videos/{kept}/delete", {})[0] == 400  # no CSRF token
    assert _videos(live_server) == [kept]
