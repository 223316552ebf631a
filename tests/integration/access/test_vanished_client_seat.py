"""A client that vanishes without closing (its connection just stops answering) loses its seat one grace period
after it was last heard, not when its socket finally times out; a quiet client that answers pings keeps it."""

from __future__ import annotations

import base64
import os
import socket
import time
from datetime import timedelta

from middleware.access.coordinator import access_coordinator
from middleware.auth.services import create_user
from middleware.db import session_factory
from tests.conftest import STUDENT_PASSWORD, LabClient
from tests.integration.lab.test_robot_channels import receive_json

GRACE_S = 15.0  # the documented default (TELELAB_GRACE_S)
LATE_MARGIN_S = 5.0  # the ticker's period and a loaded machine; the old behaviour took about 54 s


def _open_and_vanish(client: LabClient, path: str) -> socket.socket:
    """A WebSocket handshake, then silence: no frame, no pong, no close; the TCP connection stays up."""
    host, port = client.base_url.removeprefix("http://").split(":")
    raw = socket.create_connection((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    raw.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                 f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nCookie: {client.cookie_header()}\r\n"
                 "\r\n").encode())
    answer = b""
    while b"\r\n\r\n" not in answer:
        answer += raw.recv(4096)
    assert answer.startswith(b"HTTP/1.1 101"), answer
    return raw


def wait_for_the_seat(coordinator, robot_name: str, vanished_at: float) -> int:
    """The vanishing client's user id, once it holds robot_name's seat (within 10 s of its handshake)."""
    while coordinator.snapshot(robot_name).controller_id is None:
        assert time.monotonic() < vanished_at + 10, "the vanishing client never got its seat"
        time.sleep(0.05)
    return coordinator.snapshot(robot_name).controller_id


def test_a_vanished_client_loses_its_seat_within_the_grace_and_a_quiet_one_keeps_it(live_server,
                                                                                      student_client) -> None:
    app = live_server.app
    assert app.config["ACCESS_GRACE_S"] == GRACE_S
    with session_factory(app)() as session:
        quiet_id = create_user(session, "quiet", "student", STUDENT_PASSWORD).id
        session.commit()
    quiet = LabClient(live_server.url)
    assert quiet.login("quiet", STUDENT_PASSWORD) == 302
    coordinator = access_coordinator(app)

    vanished = _open_and_vanish(student_client, "/ws/robots/lab-1/queue")
    vanished_at = time.monotonic()
    try:
        vanished_id = wait_for_the_seat(coordinator, "lab-1", vanished_at)
        quiet_socket = quiet.websocket("/ws/robots/lab-1/queue")  # answers pings, sends nothing
        assert receive_json(quiet_socket)["type"] == "queue"
        while coordinator.snapshot("lab-1").controller_id == vanished_id:
            assert time.monotonic() - vanished_at < GRACE_S + LATE_MARGIN_S, "the vanished client kept its seat"
            time.sleep(0.2)
        lost_after_s = time.monotonic() - vanished_at
        print(f"\nthe vanished client lost its seat {lost_after_s:.1f} s after it went quiet")
        assert lost_after_s > GRACE_S - 1.0, "the seat went before the grace was over"
        state = coordinator.snapshot("lab-1")
        assert state.controller_id == quiet_id and vanished_id not in state.waiting_ids
    finally:
        quiet.close()
        vanished.close()


def test_a_closed_socket_s_seat_counts_its_grace_from_the_close(live_server, student_client) -> None:
    """A reload closes the console's sockets: the close is heard, and written with the process's next batch of seat
    times (one write for a whole class closing at once), so the grace counts from the close."""
    from sqlalchemy import select

    from middleware.access.coordinator import HEARD_WRITE_S
    from middleware.models import QueueEntry

    app = live_server.app
    coordinator = access_coordinator(app)
    queue_socket = student_client.websocket("/ws/robots/lab-1/queue")
    assert receive_json(queue_socket)["type"] == "queue"
    time.sleep(1.0)  # less than a heartbeat interval after the socket's first word
    closed_at = coordinator.clock()
    queue_socket.close()
    deadline = time.monotonic() + HEARD_WRITE_S + 2.0
    while True:
        with session_factory(app)() as session:
            heard = session.scalar(select(QueueEntry.last_seen_at).where(QueueEntry.robot_name == "lab-1"))
        assert heard is not None, "the seat was dropped at the close"
        if heard.replace(tzinfo=None) >= closed_at.replace(tzinfo=None) - timedelta(seconds=0.5):
            break
        assert time.monotonic() < deadline, f"the close was not written: last heard {heard}, closed {closed_at}"
        time.sleep(0.1)
