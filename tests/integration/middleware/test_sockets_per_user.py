"""One user cannot hold the web process's threads: past MAX_SOCKETS_PER_USER open sockets, a handshake is
refused with 429 before it costs a thread; closing one makes room, and other users are not affected."""

from __future__ import annotations

import time

from tests.conftest import STUDENT_PASSWORD, LabClient
from tests.integration.middleware.test_websocket_compression import handshake_answer

CHANNEL = "/ws/robots/lab-1/chat"


def _status(answer: str) -> int:
    return int(answer.split(" ", 2)[1])


def test_a_user_at_the_socket_limit_is_refused_and_others_are_not(student_client: LabClient, live_server) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.realtime import MAX_SOCKETS_PER_USER

    with session_factory(live_server.app)() as session:
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
    held = [student_client.websocket(CHANNEL) for _ in range(MAX_SOCKETS_PER_USER)]
    assert all(ws.receive(timeout=5) is not None for ws in held)  # each got its history: all open
    refused = handshake_answer(student_client, CHANNEL, "")
    assert _status(refused) == 429, refused
    other = LabClient(student_client.base_url)
    assert other.login("student2") == 302
    assert _status(handshake_answer(other, CHANNEL, "")) == 101
    held.pop().close()
    deadline = time.monotonic() + 5
    while _status(handshake_answer(student_client, CHANNEL, "")) != 101:
        assert time.monotonic() < deadline, "closing a socket did not make room for another"
        time.sleep(0.1)
