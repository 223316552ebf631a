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
        assert status == 202 and started["starting"], started  # started once the claim is committed
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


def test_a_telelab_command_beside_the_web_server_leaves_its_local_robots_alone(live_server) -> None:
    import os
    import subprocess
    import sys

    from middleware.teaching.practice_robots import practice_manager

    ann = _client(live_server, "ann", "student")
    environment = {**os.environ, "TELELAB_DATABASE_URL": live_server.app.config["DATABASE_URL"],
                   "TELELAB_FARM": "local", "TELELAB_ROBOTS": ""}
    try:
        assert _api(ann, "POST", "/api/practice")[0] == 202

        def telelab(*args: str) -> subprocess.CompletedProcess[str]:
            return subprocess.run([sys.executable, "-m", "middleware.cli", *args], env=environment,
                                  capture_output=True, text=True, timeout=120)

        status = telelab("farm", "status")
        assert status.returncode == 0, status.stderr
        assert "practice-ann" in status.stdout and "another process" in status.stdout
        stop = telelab("farm", "stop", "practice-ann")
        assert stop.returncode == 1 and "/admin/farm" in stop.stderr
        status, seen = _api(ann, "GET", "/api/practice")  # the commands' own app did not forget the robot
        assert status == 200 and seen["running"] and seen["name"] == "practice-ann"
        status, ran = _api(ann, "POST", "/api/practice/commands", {"command": {"stop": True}})
        assert status == 202, ran
    finally:
        practice_manager(live_server.app).shutdown()


def test_a_farm_replaces_a_robot_of_the_same_name_started_for_another_token() -> None:
    from middleware.farm.base import RobotSpec
    from middleware.farm.local import LocalProcessFarm
    from middleware.robots.link import CommandRefused, RobotLink

    farm = LocalProcessFarm()
    try:
        first = farm.start(RobotSpec("practice-zed", "empty", "old-token"))
        assert farm.start(RobotSpec("practice-zed", "empty", "old-token")).address == first.address
        second = farm.start(RobotSpec("practice-zed", "empty", "new-token"))
        link = RobotLink("practice-zed", second.address)
        try:
            assert link.drive("new-token", 1, 0.1, 0.0).applied_sequence == 1
            try:
                link.drive("old-token", 2, 0.1, 0.0)
                raise AssertionError("the replaced robot's token still drives")
            except CommandRefused:
                pass
        finally:
            link.close()
        assert len(farm.robots()) == 1
    finally:
        farm.close()
