"""Robot pools over real skill servers and a served app: students claim, wait for and book "any robot of a kind";
the robot is bound when a turn or a slot starts; a full pool answers 409 with the expected wait and keeps nothing."""

from __future__ import annotations

import time
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, make_course, served_lab
from tests.integration.teaching.test_practice_console_and_uploads import _api

TURN_S = 3.0


@pytest.fixture(scope="module")
def second_robot() -> Iterator[str]:
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    robot = SkillServerProcess("sim-2", "lab")
    robot.start()
    try:
        wait_until_serving(robot.address)
        yield robot.address
    finally:
        robot.stop()


@pytest.fixture
def lab(tmp_path, skill_server_address: str, second_robot: str):
    with served_lab(f"sim-1={skill_server_address},sim-2={second_robot},solo-1={skill_server_address}",
                    tmp_path) as server:
        server.app.config["DEFAULT_TURN_LENGTH_S"] = TURN_S
        server.app.config["ACCESS_GRACE_S"] = 60.0
        yield server


def _student(lab, name: str) -> LabClient:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    if name != "student1":
        with session_factory(lab.app)() as session:
            create_user(session, name, "student", STUDENT_PASSWORD)
            session.commit()
    client = LabClient(lab.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def _controller(lab, robot: str) -> int | None:
    from middleware.access.coordinator import access_coordinator

    return access_coordinator(lab.app).snapshot(robot).controller_id


def _user_id(lab, name: str) -> int:
    from middleware.auth.services import find_user
    from middleware.db import session_factory

    with session_factory(lab.app)() as session:
        return find_user(session, name).id


def test_students_claim_free_robots_then_a_full_pool_says_the_wait_and_the_queue_binds_at_the_turns_end(lab) -> None:
    from middleware.db import session_factory
    from middleware.models import PoolQueueEntry

    ann, bob, cy = (_student(lab, n) for n in ("student1", "bob", "cy"))
    status, first = _api(ann, "POST", "/api/pools/sim/claim")
    assert status == 200 and first["robot_name"] in ("sim-1", "sim-2") and first["position"] == 0
    assert first["console_url"] == f"/lab/{first['robot_name']}"
    status, second = _api(bob, "POST", "/api/pools/sim/claim")
    assert status == 200 and {first["robot_name"], second["robot_name"]} == {"sim-1", "sim-2"}
    assert _controller(lab, first["robot_name"]) == _user_id(lab, "student1")

    status, full = _api(cy, "POST", "/api/pools/sim/claim")
    assert status == 409 and full["error"]["code"] == "pool_full" and full["error"]["field"] == "kind"
    assert "All 2 robots of kind 'sim' are in use" in full["error"]["message"]
    assert full["error"]["expected_wait_s"] == pytest.approx(TURN_S, abs=0.5)
    with session_factory(lab.app)() as session:
        assert session.query(PoolQueueEntry).count() == 0, "a refused claim queues nobody"

    status, waiting = _api(cy, "POST", "/api/pools/sim/queue")
    assert status == 200 and waiting["robot_name"] is None and waiting["position"] == 1
    assert waiting["robots"] == 2 and 0 < waiting["estimated_wait_s"] <= TURN_S
    deadline = time.monotonic() + TURN_S + 10
    while waiting["robot_name"] is None:
        assert time.monotonic() < deadline, "cy was never bound to a robot"
        time.sleep(0.5)
        for client in (ann, bob):  # the controllers stay connected, as their consoles would
            _api(client, "POST", "/api/pools/sim/queue")
        status, waiting = _api(cy, "POST", "/api/pools/sim/queue")
        assert status == 200
    assert _controller(lab, waiting["robot_name"]) == _user_id(lab, "cy")
    assert cy.request("GET", waiting["console_url"])[0] == 200


def test_unknown_pools_and_bad_kinds_are_refused_naming_the_field(lab) -> None:
    ann = _student(lab, "student1")
    for path in ("/api/pools/nosuch/claim", "/api/pools/nosuch/queue", "/api/pools/nosuch/seat"):
        status, error = _api(ann, "GET" if path.endswith("seat") else "POST", path)
        assert (status, error["error"]["code"], error["error"]["field"]) == (404, "unknown_pool", "kind"), path
    status, error = _api(ann, "POST", "/api/pools/%00x/queue")
    assert (status, error["error"]["code"], error["error"]["field"]) == (400, "invalid_field", "kind")
    assert ann.request("GET", "/pools/nosuch")[0] == 404
    status, _, page = ann.request("GET", "/lab")
    assert status == 200 and 'data-pool="sim"' in page and 'data-pool="solo"' not in page


def test_pool_bookings_hold_as_many_slots_as_the_kind_has_robots(lab) -> None:
    clients = [_student(lab, name) for name in ("student1", "bob", "cy")]
    make_course(lab.app, "POOL", {"student1": "student", "bob": "student", "cy": "student"})  # a weekly allowance
    start = (datetime.now(UTC) + timedelta(days=2)).replace(hour=10, minute=0, second=0, microsecond=0)
    slot = {"pool": "sim", "starts_at": start.isoformat().replace("+00:00", "Z"), "duration_min": 60}
    for client in clients[:2]:
        status, booked = _api(client, "POST", "/api/bookings", slot)
        assert status == 201 and booked["booking"]["robot_name"] is None and booked["booking"]["pool"] == "sim"
    status, full = _api(clients[2], "POST", "/api/bookings", slot)
    assert status == 409 and full["error"]["code"] == "pool_full"
    later = (start + timedelta(hours=1)).strftime("%Y-%m-%d %H:%M")
    assert f"first slot as long that fits starts at {later} UTC" in full["error"]["message"]
    status, named = _api(clients[2], "POST", "/api/bookings", {**slot, "pool": "", "robot_name": "sim-1"})
    assert status == 409 and named["error"]["code"] == "slot_taken" and "any sim robot" in named["error"]["message"]
    status, other = _api(clients[2], "POST", "/api/bookings", {**slot, "pool": "nosuch"})
    assert (status, other["error"]["code"], other["error"]["field"]) == (404, "unknown_pool", "pool")
    status, _, page = clients[0].request("GET", "/bookings?robot=sim-1")
    assert status == 200 and "any sim robot" in page and 'id="booking-pool"' in page
