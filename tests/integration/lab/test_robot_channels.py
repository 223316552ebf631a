"""The WebSocket channels against a real skill server: drive, camera and telemetry relays, refusals."""

from __future__ import annotations

import json
import time

import pytest
import simple_websocket

from middleware.robots.messages import unpack_camera_frame
from tests.conftest import LabClient


def receive_json(ws, timeout_s: float = 5.0) -> dict:
    """The next text message, skipping binary ones."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        message = ws.receive(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(message, str):
            return json.loads(message)
    raise AssertionError("no text message arrived")


def steady_telemetry(ws, steady_s: float = 0.3, within_s: float = 5.0) -> dict:
    """The newest telemetry once its applied sequence has not changed for steady_s (a new controller's token takes
    effect at the robot's next tick, later than that under load)."""
    deadline = time.monotonic() + within_s
    message = next_telemetry(ws)
    since = time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.05)
        newest = next_telemetry(ws)
        if newest["last_applied_sequence"] != message["last_applied_sequence"]:
            since = time.monotonic()
        message = newest
        if time.monotonic() - since >= steady_s:
            return message
    raise AssertionError(f"the applied sequence did not settle within {within_s} s")


def next_telemetry(ws) -> dict:
    """The newest telemetry message: older ones queued in the socket are skipped."""
    newest = None
    while (pending := ws.receive(timeout=0)) is not None:
        if isinstance(pending, str) and json.loads(pending)["type"] == "telemetry":
            newest = json.loads(pending)
    while newest is None:
        message = receive_json(ws)
        if message["type"] == "telemetry":
            newest = message
    return newest


def closed_with(ws, timeout_s: float = 5.0) -> int:
    """The close code the server sent."""
    deadline = time.monotonic() + timeout_s
    try:
        while time.monotonic() < deadline:
            ws.receive(timeout=0.1)
    except simple_websocket.ConnectionClosed as closed:
        return closed.reason
    raise AssertionError("the socket stayed open")


def pose(telemetry: dict) -> tuple[float, float, float]:
    p = telemetry["odometry"]["pose"]
    return p["x_m"], p["y_m"], p["theta_rad"]


class _SlowReader:
    """A socket whose first read waits, so the server's answer and the frames after it arrive as one read."""

    def __init__(self, sock) -> None:
        self._sock, self._waited = sock, False

    def recv(self, size: int) -> bytes:
        if not self._waited:
            self._waited = True
            time.sleep(0.3)
        return self._sock.recv(size)

    def __getattr__(self, name: str):
        return getattr(self._sock, name)


@pytest.mark.parametrize("client_class", ["plain", "ours"])
def test_frames_in_the_same_read_as_the_handshake_reach_the_test_client(lab_client: LabClient,
                                                                        client_class: str) -> None:
    from benchmarks.lab_under_test import WebSocketClient

    base = simple_websocket.Client if client_class == "plain" else WebSocketClient

    class Slow(base):
        def handshake(self) -> None:
            self.sock = _SlowReader(self.sock)
            super().handshake()

    ws = Slow.connect(lab_client.base_url.replace("http", "ws", 1) + "/ws/robots/lab-1/drive")
    if client_class == "plain":  # simple_websocket's own client loses them: the reason for WebSocketClient
        with pytest.raises(simple_websocket.ConnectionClosed) as lost:
            ws.receive(timeout=5)
        assert lost.value.reason == 1005
    else:
        assert json.loads(ws.receive(timeout=5))["code"] == "not_logged_in" and closed_with(ws) == 4401


def test_a_websocket_without_a_session_is_refused(lab_client: LabClient) -> None:
    for channel in ("drive", "camera", "telemetry"):
        ws = lab_client.websocket(f"/ws/robots/lab-1/{channel}")
        error = receive_json(ws)
        assert error["type"] == "error" and error["code"] == "not_logged_in"
        assert closed_with(ws) == 4401


def test_a_websocket_from_another_site_is_refused(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/robots/lab-1/drive", origin="https://evil.example")
    assert receive_json(ws)["code"] == "forbidden_origin"
    assert closed_with(ws) == 4403


def test_an_unknown_robot_is_refused_by_name(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/robots/nope/drive")
    error = receive_json(ws)
    assert error["code"] == "unknown_robot" and error["field"] == "robot_name"
    assert closed_with(ws) == 4404


def test_an_offline_robot_asks_the_driver_to_come_back_later(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/robots/ghost/drive")
    assert receive_json(ws)["code"] == "robot_offline"
    assert closed_with(ws) == 1013


def test_a_plain_http_request_to_a_channel_gets_a_json_error(student_client: LabClient) -> None:
    status, _, body = student_client.request("GET", "/ws/robots/lab-1/drive")
    assert status == 400 and json.loads(body)["error"]["code"] == "websocket_required"


def test_telemetry_is_relayed_and_advances(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/robots/lab-1/telemetry")
    first = next_telemetry(ws)
    second = next_telemetry(ws)
    assert second["tick"] > first["tick"] and second["sim_time_s"] > first["sim_time_s"]
    assert len(first["sonar"]["ranges_m"]) > 0 and len(first["laser"]["ranges_m"]) > 0
    assert "ground_truth" not in first, "the ground truth is kept for grading, not shown"
    ws.close()


def test_camera_frames_are_relayed_with_advancing_metadata(student_client: LabClient) -> None:
    ws = student_client.websocket("/ws/robots/lab-1/camera")
    headers = []
    while len(headers) < 3:
        message = ws.receive(timeout=5)
        assert message is not None, "no camera frame within 5 s"
        if isinstance(message, bytes):
            header, jpeg = unpack_camera_frame(message)
            assert jpeg[:2] == b"\xff\xd8"
            assert (header["width_px"], header["height_px"]) == (320, 240)
            headers.append(header)
    assert headers[0]["frame_sequence"] < headers[1]["frame_sequence"] < headers[2]["frame_sequence"]
    assert headers[0]["capture_unix_s"] < headers[2]["capture_unix_s"]
    ws.close()


def drive_for(ws, seconds: float, linear: float, angular: float, first_sequence: int) -> int:
    """Sends the command at 20 Hz for seconds, as a browser holding a key does; returns the last sequence."""
    sequence = first_sequence
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ws.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": linear, "angular_radps": angular}))
        ack = receive_json(ws)
        assert ack["type"] == "ack" and ack["sequence"] == sequence, ack
        sequence += 1
        time.sleep(0.05)
    return sequence - 1


def test_driving_over_the_websocket_moves_the_robot_and_closing_stops_it(student_client: LabClient) -> None:
    telemetry = student_client.websocket("/ws/robots/lab-1/telemetry")
    drive = student_client.websocket("/ws/robots/lab-1/drive")
    ready = receive_json(drive)
    assert ready["type"] == "ready" and ready["max_linear_mps"] > 0
    before = pose(next_telemetry(telemetry))
    last = drive_for(drive, 1.0, 0.3, 0.0, 1)
    moving = next_telemetry(telemetry)
    assert moving["odometry"]["linear_mps"] > 0.1
    drive.close()
    closed_at = time.monotonic()
    # Within half a second of the socket closing the robot must be still.
    while True:
        sample = next_telemetry(telemetry)
        if abs(sample["odometry"]["linear_mps"]) < 0.02:
            break
        assert time.monotonic() - closed_at < 0.5, "the robot still moved half a second after the driver left"
    after = pose(sample)
    travelled = ((after[0] - before[0]) ** 2 + (after[1] - before[1]) ** 2) ** 0.5
    assert 0.15 < travelled < 0.45, f"1 s at 0.3 m/s moved the robot {travelled:.3f} m"
    assert last >= 10
    telemetry.close()


@pytest.mark.parametrize(
    ("message", "field"),
    [
        ("this is not json", "message"),
        ('{"type": "drive", "sequence": 1, "linear_mps": NaN, "angular_radps": 0}', "linear_mps"),
        ('{"type": "drive", "sequence": 1, "linear_mps": 1e9, "angular_radps": 0}', "linear_mps"),
        ('{"type": "drive", "sequence": 1, "linear_mps": 0.1, "angular_radps": -1e9}', "angular_radps"),
        ('{"type": "drive", "sequence": "one", "linear_mps": 0.1, "angular_radps": 0}', "sequence"),
        ('{"type": "fly", "sequence": 1}', "type"),
    ],
)
def test_malformed_drive_messages_are_refused_and_the_robot_does_not_move(
    student_client: LabClient, message: str, field: str
) -> None:
    telemetry = student_client.websocket("/ws/robots/lab-1/telemetry")
    drive = student_client.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    settled = steady_telemetry(telemetry)  # joining handed the robot a new controller token; let telemetry show it
    drive.send(message)
    error = receive_json(drive)
    assert error["type"] == "error" and error["field"] == field and error["message"]
    time.sleep(0.3)
    later = next_telemetry(telemetry)
    assert later["last_applied_sequence"] == settled["last_applied_sequence"]
    assert abs(later["odometry"]["linear_mps"]) < 0.02 and abs(later["odometry"]["angular_radps"]) < 0.05
    # The socket stays usable after a bad message.
    drive.send(json.dumps({"type": "stop", "sequence": 1}))
    assert receive_json(drive)["type"] == "ack"
    drive.close()
    telemetry.close()
