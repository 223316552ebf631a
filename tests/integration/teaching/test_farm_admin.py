"""The robot farm's admin page and API: capacity, hosts and robots with owners and load; stopping a robot; a farm
that cannot be reached is said on the page; nobody but an admin sees any of it."""

from __future__ import annotations

import socket

from tests.conftest import STUDENT_PASSWORD, LabClient
from tests.integration.teaching.test_practice_console_and_uploads import _api


def _client(live_server, name: str, role: str) -> LabClient:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        create_user(session, name, role, STUDENT_PASSWORD)
        session.commit()
    client = LabClient(live_server.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def test_an_admin_sees_the_farm_and_stops_a_practice_robot(live_server) -> None:
    from middleware.teaching.practice_robots import practice_manager

    admin, ann = _client(live_server, "root", "admin"), _client(live_server, "ann", "student")
    try:
        status, started = _api(ann, "POST", "/api/practice")
        assert status == 201, started
        status, farm = _api(admin, "GET", "/api/admin/farm")
        assert status == 200 and farm["backend"] == "local" and farm["capacity"]["running"] == 1
        assert farm["capacity"]["robots"] >= 1 and farm["hosts"][0]["robots"] == 1
        (robot,) = farm["robots"]
        assert robot["name"] == "practice-ann" and robot["owner"] == "ann" and robot["memory_mb"] > 10
        status, _, page = admin.request("GET", "/admin/farm")
        assert status == 200 and 'data-robot="practice-ann"' in page and "Stop practice-ann" in page
        assert ann.request("GET", "/admin/farm")[0] == 403
        assert _api(ann, "GET", "/api/admin/farm")[0] == 403

        token = admin.csrf_token("/admin/farm")
        status, headers, _ = admin.request("POST", "/admin/farm/robots/practice-ann/stop", {"csrf_token": token})
        assert status == 303 and headers["Location"].endswith("/admin/farm")
        status, seen = _api(ann, "GET", "/api/practice")
        assert status == 200 and not seen["running"]  # its owner sees it stopped
        status, _, page = admin.request("POST", "/admin/farm/robots/practice-ann/stop", {"csrf_token": token})
        assert status == 404 and "no robot of that name" in page
    finally:
        practice_manager(live_server.app).shutdown()


def test_an_unreachable_farm_is_said_on_the_page(live_server) -> None:
    from middleware.farm.ray_farm import RayFarm

    admin = _client(live_server, "root", "admin")
    with socket.socket() as unused:
        unused.bind(("127.0.0.1", 0))
        port = unused.getsockname()[1]
    extensions = live_server.app.extensions
    real, extensions["telelab.farm"] = extensions["telelab.farm"], RayFarm(f"127.0.0.1:{port}")
    try:
        status, _, page = admin.request("GET", "/admin/farm")
        assert status == 503 and f"127.0.0.1:{port} cannot be reached" in page and 'id="farm-problem"' in page
        status, error = _api(admin, "GET", "/api/admin/farm")
        assert (status, error["error"]["code"]) == (503, "farm_unavailable")
    finally:
        extensions["telelab.farm"] = real
