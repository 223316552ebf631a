"""A student's first write after a minute without requests, on SQLite (what `make run` uses): the login's "last
seen" touch is due, and the request must not stall on SQLite's write lock while the access ticker and the seats'
"last heard" batches write beside it. Each write here once waited the 15 s busy timeout and answered 500."""

from __future__ import annotations

import json
import threading
import traceback
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from urllib.request import Request

import pytest
from sqlalchemy import update

from tests.conftest import LabClient, served_lab


@pytest.fixture
def lab(tmp_path, skill_server_address: str) -> Iterator:
    with served_lab(f"sim-1={skill_server_address}", tmp_path) as server:
        yield server


def send_json(client: LabClient, token: str, method: str, path: str) -> tuple[int, dict]:
    """(status, JSON body) of one API request with the page's CSRF token."""
    request = Request(client.base_url + path, data=b"{}" if method != "GET" else None, method=method,
                      headers={"Content-Type": "application/json", "X-CSRFToken": token, "Accept": "application/json"})
    try:
        with client._opener.open(request, timeout=30) as response:
            return response.status, json.loads(response.read())
    except Exception as error:  # noqa: BLE001 - 4xx/5xx are answers here
        return error.code, json.loads(error.read() or b"{}")


def _idle_for_two_minutes(app) -> None:
    """As if the student sent nothing for two minutes: their login's touch is due on the next request."""
    from middleware.auth import identity, session_records
    from middleware.db import session_factory
    from middleware.models import LoginSession

    with session_factory(app)() as session, session.begin():
        session.execute(update(LoginSession).values(last_seen_at=datetime.now(UTC) - timedelta(minutes=2)))
    session_records.forget_verdicts(None)
    for user_id in range(1, 10):
        identity.forget(user_id)  # the process's copy of the user is older than its 5 s too


class BackgroundWriters:
    """The access ticker and the seats' "last heard" batch, writing as they do in a served lab, with their
    failures kept."""

    def __init__(self, app, user_id: int) -> None:
        from middleware.access.coordinator import access_coordinator

        self._coordinator = access_coordinator(app)
        self._user_id = user_id
        self.failures: list[str] = []
        self.writes = 0
        self._stop = threading.Event()
        self._first = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            self._stop.wait(0.05)
            try:
                self._coordinator.tick("sim-1")
                self._coordinator.note_heard("sim-1", self._user_id)
                self._coordinator.heard.write()
                self.writes += 1
            except Exception:  # noqa: BLE001 - what failed is the finding
                self.failures.append(traceback.format_exc())
            self._first.set()

    def __enter__(self) -> BackgroundWriters:
        self._thread.start()
        self._first.wait(30)  # the writers run before and while the request does
        return self

    def __exit__(self, *_exc: object) -> None:
        self._stop.set()
        self._thread.join(30)


def _student(lab) -> tuple[LabClient, str, int]:
    from middleware.auth.services import find_user
    from middleware.db import session_factory

    client = LabClient(lab.url)
    assert client.login() == 302
    token = client.csrf_token("/lab")
    with session_factory(lab.app)() as session:
        return client, token, find_user(session, "student1").id


WRITES = [("POST", "/api/pools/sim/queue"), ("DELETE", "/api/pools/sim/queue"), ("POST", "/api/pools/sim/claim")]


@pytest.mark.parametrize(("method", "path"), WRITES, ids=["heartbeat", "leave", "claim"])
def test_the_first_pool_write_after_idle_answers_at_once_beside_the_ticker_and_the_seats(lab, method, path) -> None:
    client, token, user_id = _student(lab)
    if method == "DELETE":
        assert send_json(client, token, "POST", "/api/pools/sim/queue")[0] == 200
    for attempt in range(2):  # it failed twice in a row: nothing committed the touch in between
        _idle_for_two_minutes(lab.app)
        with BackgroundWriters(lab.app, user_id) as writers:
            status, body = send_json(client, token, method, path)
        assert status == 200, (attempt, body)
        assert writers.failures == [], writers.failures
        assert writers.writes > 0


def test_a_robot_channel_opened_after_idle_joins_the_queue_beside_the_ticker(lab) -> None:
    client, _token, user_id = _student(lab)
    _idle_for_two_minutes(lab.app)
    with BackgroundWriters(lab.app, user_id) as writers:
        ws = client.websocket("/ws/robots/sim-1/queue")
        message = json.loads(ws.receive(timeout=30))
    assert message.get("type") != "error" and ws.connected, message
    assert writers.failures == [], writers.failures
