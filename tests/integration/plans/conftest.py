"""A lab on SQLite and on PostgreSQL for the plans tests: student1 and student2 in course ROB1 taught by tutor1,
tutor2 teaching ROB2, admin1; wired to the session's real skill server (plans are checked against its skills)."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from urllib.request import Request

import pytest

from tests.conftest import (
    STUDENT_PASSWORD,
    LabClient,
    LiveServer,
    _let_go,
    add_test_account,
    make_course,
    make_test_app,
)

PEOPLE = {"student2": "student", "student3": "student", "tutor1": "tutor", "tutor2": "tutor", "admin1": "admin"}


@dataclass
class PlansLab:
    """The served lab and its course ids."""

    server: LiveServer
    course: int
    other_course: int

    def client(self, username: str) -> LabClient:
        """A client logged in as username."""
        client = LabClient(self.server.url)
        assert client.login(username, STUDENT_PASSWORD) == 302
        return client


@pytest.fixture
def plans_lab(database_url: str, tmp_path: Path, skill_server_address: str) -> Iterator[PlansLab]:
    """The app on database_url (SQLite, then PostgreSQL) with the people above, served."""
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager

    app = make_test_app(database_url, f"lab-1={skill_server_address}", tmp_path)
    with session_factory(app)() as session:
        for name, role in PEOPLE.items():
            add_test_account(session, name, role)
        session.commit()
    course = make_course(app, "ROB1", {"student1": "student", "student2": "student", "tutor1": "tutor"})
    other = make_course(app, "ROB2", {"student3": "student", "tutor2": "tutor"})
    server = LiveServer(app)
    try:
        yield PlansLab(server, course, other)
    finally:
        practice_manager(app).shutdown()
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()  # before the PostgreSQL database is dropped


def api(client: LabClient, method: str, path: str, body: object | None = None,
        raw: bytes | None = None, content_type: str | None = None) -> tuple[int, dict]:
    """A request as the page sends it (CSRF header, JSON body, or raw bytes with content_type); (status, JSON)."""
    headers = {"X-CSRFToken": client.csrf_token("/plans"), "Accept": "application/json"}
    data = raw
    if body is not None:
        data, headers["Content-Type"] = json.dumps(body).encode(), "application/json"
    elif content_type is not None:
        headers["Content-Type"] = content_type
    request = Request(client.base_url + path, data=data, method=method, headers=headers)
    try:
        with client._opener.open(request, timeout=60) as response:
            payload = response.read()
            if response.headers.get_content_type() == "application/json" and \
                    "attachment" not in response.headers.get("Content-Disposition", ""):
                return response.status, json.loads(payload)
            return response.status, {"body": payload.decode(), "headers": dict(response.headers)}
    except Exception as error:
        if hasattr(error, "code"):
            return error.code, json.loads(error.read() or b"{}")
        raise


def run_on_practice(client: LabClient, plan_id: int, body: dict[str, object],
                    timeout_s: float = 60) -> tuple[int, dict]:
    """Runs a plan on the practice robot as the page does: a robot not running yet is claimed (202, starting, no
    goal) and started once that claim is committed; GET /api/practice follows it to running, then the run is asked
    again. (status, answer) of the run that started the plan, or of the first refusal."""
    import time

    path = f"/api/plans/{plan_id}/runs"
    status, answer = api(client, "POST", path, {"target": "practice", **body})
    if status != 202 or not answer.get("starting"):
        return status, answer
    assert answer["goal"] is None and answer["status_url"] == "/api/practice", answer
    deadline = time.monotonic() + timeout_s
    while True:
        seen_status, seen = api(client, "GET", answer["status_url"])
        assert seen_status == 200, seen
        if seen["running"]:
            break
        assert seen["starting"], f"the practice robot stopped starting without running: {seen}"
        assert time.monotonic() < deadline, f"the practice robot did not start within {timeout_s} s"
        time.sleep(0.2)
    status, answer = api(client, "POST", path, {"target": "practice", **body})
    assert status != 202 or not answer["starting"], answer  # it runs, in the scene asked: the plan runs now
    return status, answer


def upload(client: LabClient, path: str, filename: str, content: bytes, fields: dict[str, str] | None = None
           ) -> tuple[int, dict]:
    """A multipart upload of one file (field "file") and form fields."""
    boundary = "----telelab-plans-test"
    parts = []
    for name, value in (fields or {}).items():
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'.encode())
    parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="file"; filename="{filename}"\r\n'
                 f"Content-Type: application/octet-stream\r\n\r\n".encode() + content + b"\r\n")
    parts.append(f"--{boundary}--\r\n".encode())
    return api(client, "POST", path, raw=b"".join(parts), content_type=f"multipart/form-data; boundary={boundary}")


ApiCall = Callable[..., tuple[int, dict]]
