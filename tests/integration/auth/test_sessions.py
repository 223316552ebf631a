"""Server-side sessions across two web worker processes on one database: a cookie replayed after logout, a
password change or disabling the account opens nothing in either worker; Secure cookies over HTTPS."""

from __future__ import annotations

import os
import secrets
import subprocess
import sys
import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from benchmarks.ports import free_port
from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, add_test_account, migrate_to_head

ROOT = Path(__file__).resolve().parents[3]
REFUSED_WITHIN_S = 10.0  # a worker keeps a verdict RECHECK_S (1 s); the margin is for a loaded machine


@pytest.fixture
def workers(database_url: str, tmp_path: Path) -> Iterator[tuple[LiveServer, str]]:
    """Worker 1 served in this process, worker 2 a `telelab web` process; same database and secret key."""
    from middleware import create_app
    from middleware.db import session_factory

    secret = secrets.token_hex(16)
    migrate_to_head(database_url)
    app = create_app({"DATABASE_URL": database_url, "SECRET_KEY": secret, "ROBOTS": (), "TESTING": True})
    with session_factory(app)() as session:
        add_test_account(session, "student1", "student")
        add_test_account(session, "admin1", "admin")
        session.commit()
    first = LiveServer(app)
    port = free_port()
    env = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": secret, "TELELAB_ROBOTS": ""}
    second = subprocess.Popen([sys.executable, "-m", "middleware.cli", "web", "--host", "127.0.0.1", "--port",
                               str(port)], cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                if LabClient(url).request("GET", "/healthz")[0] == 200:
                    break
            except OSError:
                pass
            assert second.poll() is None and time.monotonic() < deadline, "worker 2 did not start"
            time.sleep(0.2)
        yield first, url
    finally:
        second.terminate()
        second.wait(timeout=30)
        first.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()  # before the database is dropped


def _replay(url: str, cookie: str, path: str = "/api/bookings") -> tuple[int, dict[str, str]]:
    status, headers, _ = LabClient(url).request("GET", path, headers={"Cookie": cookie})
    return status, headers


def _refused_soon(url: str, cookie: str) -> None:
    """The API answers 401 and a page redirects to the login, within REFUSED_WITHIN_S."""
    deadline = time.monotonic() + REFUSED_WITHIN_S
    while _replay(url, cookie)[0] != 401:
        assert time.monotonic() < deadline, f"{url} still accepts the cookie"
        time.sleep(0.2)
    status, headers = _replay(url, cookie, "/account/password")
    assert status == 302 and "/login" in headers["Location"]


def _logged_in(url: str, username: str = "student1") -> LabClient:
    client = LabClient(url)
    assert client.login(username) == 302
    return client


def test_a_cookie_replayed_after_logout_is_refused_in_both_workers(workers) -> None:
    first, second = workers
    student = _logged_in(first.url)
    cookie = student.cookie_header()
    assert _replay(second, cookie)[0] == 200, "another client and another worker accept the open login"
    token = student.csrf_token("/account/password")
    assert student.request("POST", "/logout", {"csrf_token": token})[0] == 302
    assert _replay(first.url, cookie)[0] == 401, "the worker that logged out refuses it at once"
    _refused_soon(second, cookie)


def test_a_password_change_ends_the_accounts_other_logins_in_both_workers(workers) -> None:
    first, second = workers
    changer, elsewhere = _logged_in(first.url), _logged_in(second)
    old_cookie = changer.cookie_header()
    token = changer.csrf_token("/account/password")
    status, _, _ = changer.request("POST", "/account/password", {
        "csrf_token": token, "current_password": STUDENT_PASSWORD, "new_password": "a-new-long-secret",
        "new_password_again": "a-new-long-secret"})
    assert status == 303
    assert changer.request("GET", "/api/bookings")[0] == 200, "the session that changed it stays"
    assert _replay(second, changer.cookie_header())[0] == 200
    _refused_soon(first.url, old_cookie)
    _refused_soon(second, elsewhere.cookie_header())
    _refused_soon(second, old_cookie)


def test_disabling_an_account_ends_its_logins_in_both_workers(workers) -> None:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import User

    first, second = workers
    student, admin = _logged_in(first.url), _logged_in(second, "admin1")
    cookie = student.cookie_header()
    assert _replay(second, cookie)[0] == 200
    with session_factory(first.app)() as session:
        student_id = session.scalar(select(User.id).where(User.username == "student1"))
    token = admin.csrf_token("/admin/users")
    assert admin.request("POST", f"/admin/users/{student_id}/active", {"csrf_token": token, "active": "0"})[0] == 303
    _refused_soon(first.url, cookie)
    _refused_soon(second, cookie)


def test_a_login_ends_after_its_idle_timeout_and_its_lifetime(workers) -> None:
    from middleware.auth import session_records
    from middleware.auth.session_records import SessionLimits
    from middleware.db import session_factory

    first, _ = workers
    limits = SessionLimits(lifetime=timedelta(hours=8), idle=timedelta(minutes=30))
    start = datetime.now(UTC)
    with session_factory(first.app)() as session:
        key = session_records.open_session(session, 1, start)
        session.commit()
        in_use = start + timedelta(minutes=29)
        assert session_records.is_open(session, key, 1, limits, in_use)
        session.commit()
        session_records.RECHECK_S = 0.0
        try:
            assert session_records.is_open(session, key, 1, limits, in_use + timedelta(minutes=29))
            assert not session_records.is_open(session, key, 1, limits, in_use + timedelta(minutes=60))
            assert not session_records.is_open(session, key, 2, limits, in_use), "another user's id"
            late = start + timedelta(hours=8)
            assert not session_records.is_open(session, key, 1, SessionLimits(timedelta(hours=8), timedelta(days=1)),
                                               late)
        finally:
            session_records.RECHECK_S = 1.0


@pytest.mark.parametrize(("trusted_proxies", "headers", "base_url", "secure"), [
    (0, {}, "http://lab.example", False),
    (0, {}, "https://lab.example", True),
    (0, {"X-Forwarded-Proto": "https"}, "http://lab.example", False),  # nobody trusted: anyone can send it
    (1, {"X-Forwarded-Proto": "https"}, "http://lab.example", True),
    (1, {"X-Forwarded-Proto": "http"}, "http://lab.example", False),
])
def test_the_session_cookie_is_secure_whenever_the_request_came_over_https(
    tmp_path: Path, trusted_proxies: int, headers: dict[str, str], base_url: str, secure: bool
) -> None:
    from middleware import create_app
    from middleware.db import session_factory

    url = f"sqlite:///{tmp_path / 'cookies.sqlite3'}"
    migrate_to_head(url)
    app = create_app({"DATABASE_URL": url, "SECRET_KEY": "k" * 32, "ROBOTS": (), "TRUSTED_PROXIES": trusted_proxies})
    response = app.test_client().get("/login", headers=headers, base_url=base_url)
    session_factory(app).kw["bind"].dispose()
    cookie = response.headers["Set-Cookie"]  # the CSRF token lives in the session
    assert ("; Secure" in cookie) is secure


def test_sockets_opened_before_logout_are_closed_after_it(student_client: LabClient) -> None:
    from middleware.realtime import CLOSE_NOT_LOGGED_IN, LOGIN_RECHECK_S
    from tests.integration.lab.test_robot_channels import closed_with

    paths = [f"/ws/robots/lab-1/{channel}" for channel in ("chat", "queue", "drive", "telemetry", "camera")]
    sockets = {path: student_client.websocket(path) for path in paths}
    time.sleep(0.5)
    assert all(ws.connected for ws in sockets.values())
    token = student_client.csrf_token("/account/password")
    assert student_client.request("POST", "/logout", {"csrf_token": token})[0] == 302
    for path, ws in sockets.items():  # the logout is announced: the sockets check at once, not on their timer
        assert closed_with(ws, 2.0) == CLOSE_NOT_LOGGED_IN, path
    assert LOGIN_RECHECK_S <= 5.0
