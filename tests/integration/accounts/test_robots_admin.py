"""Admins add, disable and re-enable robots; the lab follows the robots table."""

from __future__ import annotations

from benchmarks.ports import free_port
from tests.integration.bookings.conftest import api


def test_a_robot_added_at_a_closed_port_shows_offline_and_disabling_it_closes_its_console(client_as,
                                                                                        course_people) -> None:
    admin, student = client_as("admin1"), client_as("student1")
    token = admin.csrf_token("/admin/robots")
    status, headers, _ = admin.request("POST", "/admin/robots", {"name": "lab-9", "title": "Lab nine",
                                                                 "address": f"127.0.0.1:{free_port()}",
                                                                 "csrf_token": token})
    assert status == 303
    _, _, page = admin.request("GET", "/admin/robots")
    row = page.split('data-robot="lab-9"', 1)[1].split("</tr>", 1)[0]
    assert "Offline" in row
    assert student.request("GET", "/lab/lab-9")[0] == 200
    assert 'data-robot="lab-9"' in student.request("GET", "/lab")[2]

    _, robots = api(admin, "GET", "/api/admin/robots")
    robot_id = next(r["id"] for r in robots["robots"] if r["name"] == "lab-9")
    status, _ = api(admin, "PATCH", f"/api/admin/robots/{robot_id}", {"enabled": False})
    assert status == 200
    assert student.request("GET", "/lab/lab-9")[0] == 404
    assert api(student, "GET", "/api/robots/lab-9")[0] == 404
    assert 'data-robot="lab-9"' not in student.request("GET", "/lab")[2]
    assert student.request("GET", "/lab/no-such-robot")[0] == 404

    assert api(admin, "PATCH", f"/api/admin/robots/{robot_id}", {"enabled": True})[0] == 200
    assert student.request("GET", "/lab/lab-9")[0] == 200


def test_bad_robot_fields_are_shown_next_to_the_field_and_change_nothing(client_as, course_people, snapshot) -> None:
    admin = client_as("admin1")
    before = snapshot()
    token = admin.csrf_token("/admin/robots")
    status, _, page = admin.request("POST", "/admin/robots", {"name": "bad name", "address": "nowhere",
                                                              "csrf_token": token})
    assert status == 400 and 'data-error-for="name"' in page
    status, answer = api(admin, "POST", "/api/admin/robots", {"name": "ok-name", "address": "host:99999"})
    assert status == 400 and answer["error"]["field"] == "address"
    status, answer = api(admin, "POST", "/api/admin/robots", {"name": "lab-1", "address": "host:1"})
    assert status == 409 and answer["error"]["field"] == "name"
    assert snapshot() == before


def test_configured_robots_are_seeded_into_the_table(client_as, course_people) -> None:
    _, robots = api(client_as("admin1"), "GET", "/api/admin/robots")
    assert {"lab-1", "ghost"} <= {r["name"] for r in robots["robots"]}
