"""Admins see every pool's robots with their health and load, and start and stop a pool's simulated robots on the
farm (the local farm here: real skill servers as child processes); a robot the farm restarts serves again; bad
requests name their field and start nothing; nobody but an admin may do any of it."""

from __future__ import annotations

import os
import signal
import time

from tests.integration.teaching.test_farm_admin import _client
from tests.integration.teaching.test_practice_console_and_uploads import _api


def _pool_rows(app) -> dict[str, str]:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import Robot

    with session_factory(app)() as session:
        return dict(session.execute(select(Robot.name, Robot.address).where(Robot.farm_managed.is_(True))).all())


def test_an_admin_starts_a_pools_robots_a_student_gets_one_and_the_admin_stops_them(live_server) -> None:
    from middleware.farm.setup import robot_farm

    app = live_server.app
    admin, ann = _client(live_server, "root", "admin"), _client(live_server, "ann", "student")
    farm = robot_farm(app)
    try:
        status, _, page = admin.request("GET", "/admin/pools")
        assert status == 200 and 'data-pool="lab"' in page and 'data-robot="lab-1"' in page
        token = admin.csrf_token("/admin/pools")
        status, headers, _ = admin.request("POST", "/admin/pools", {"csrf_token": token, "kind": "farmsim",
                                                                    "scene": "lab", "count": "2"})
        assert status == 303, _
        rows = _pool_rows(app)
        assert sorted(rows) == ["farmsim-1", "farmsim-2"]
        assert {robot.name: robot.address for robot in farm.robots()} == rows

        status, listed = _api(ann, "GET", "/api/pools")
        farmsim = next(p for p in listed["pools"] if p["kind"] == "farmsim")
        assert farmsim == {"kind": "farmsim", "robots": 2, "online": 2, "free": 2, "queue": 0}
        status, seat = _api(ann, "POST", "/api/pools/farmsim/claim")
        assert status == 200 and seat["robot_name"] in rows
        status, _, page = admin.request("GET", "/admin/pools")
        assert 'data-pool="farmsim"' in page and "(farm, lab)" in page and ">ann<" in page

        bound = seat["robot_name"]
        pid = next(p for p in farm._processes.values() if p.name == bound).process.pid  # noqa: SLF001
        os.kill(pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while True:
            status, report = _api(admin, "GET", "/api/admin/pools")
            robots = {r["name"]: r for p in report["pools"] for r in p["robots"]}
            if robots[bound]["health"] == "ready" and farm.find(bound).restarted:
                break
            assert time.monotonic() < deadline, f"{bound} was not served again after its process died"
            time.sleep(0.5)
        assert _pool_rows(app)[bound] == farm.find(bound).address, "the row follows the restarted robot"

        status, stopped = _api(admin, "DELETE", "/api/admin/pools/farmsim")
        assert status == 200 and sorted(stopped["stopped"]) == ["farmsim-1", "farmsim-2"]
        assert _pool_rows(app) == {} and farm.robots() == []
        status, error = _api(admin, "DELETE", "/api/admin/pools/farmsim")
        assert (status, error["error"]["code"]) == (404, "unknown_pool")
    finally:
        farm.close()


def test_bad_pool_requests_name_their_field_and_start_nothing(live_server) -> None:
    from middleware.farm.setup import robot_farm

    app = live_server.app
    admin, ann = _client(live_server, "root", "admin"), _client(live_server, "ann", "student")
    try:
        for body, field in (({"kind": "x y", "scene": "lab", "count": 1}, "kind"),
                            ({"kind": "ok", "scene": "../etc", "count": 1}, "scene"),
                            ({"kind": "ok", "scene": "lab", "count": 0}, "count"),
                            ({"kind": "ok", "scene": "lab", "count": "51"}, "count"),
                            ({"kind": "ok", "scene": "lab", "count": True}, "count")):
            status, error = _api(admin, "POST", "/api/admin/pools", body)
            assert (status, error["error"]["field"]) == (400, field), body
        status, error = _api(admin, "POST", "/api/admin/pools", ["not", "an", "object"])
        assert status == 400
        status, error = _api(admin, "POST", "/api/admin/pools", {"kind": "ok", "scene": "no-such-scene", "count": 1})
        assert (status, error["error"]["code"]) == (503, "farm_unavailable")
        assert "did not start" in error["error"]["message"]
        token = admin.csrf_token("/admin/pools")
        status, _, page = admin.request("POST", "/admin/pools", {"csrf_token": token, "kind": "ok", "scene": "lab",
                                                                 "count": "many"})
        assert status == 400 and "count must be a whole number" in page
        assert _pool_rows(app) == {} and robot_farm(app).robots() == []

        assert _api(ann, "POST", "/api/admin/pools", {"kind": "ok", "scene": "lab", "count": 1})[0] == 403
        assert ann.request("GET", "/admin/pools")[0] == 403
        assert _api(ann, "GET", "/api/admin/pools")[0] == 403
    finally:
        robot_farm(app).close()
