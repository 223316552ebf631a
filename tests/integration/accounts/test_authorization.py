"""Every account and course endpoint against every role and other users' objects: refused, nothing changed.

Roles: anonymous, student1 (in ROB1), student2 (another student of ROB1), tutor1 (tutor of ROB1),
tutor2 (tutor of ROB2 only), admin1. Objects: course ROB1, student1's account, the robot 'ghost'.
Pages answer 403 (anonymous: a redirect to the login page); the API answers 401/403 JSON.
"""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import LabClient
from tests.integration.bookings.conftest import api

ALL = {"student1", "student2", "tutor1", "tutor2", "admin1"}
TEACHERS = {"tutor1", "tutor2", "admin1"}
COURSE = {"tutor1", "admin1"}
ADMIN = {"admin1"}

# (method, path, allowed logged-in users, form or JSON body). {c}: ROB1, {s}: student1, {r}: robot ghost,
# {i}: a pending invitation into ROB1.
PAGES = [
    ("GET", "/courses", TEACHERS, None),
    ("POST", "/courses", TEACHERS, {"code": "NEW1", "title": "New"}),
    ("GET", "/courses/{c}", COURSE, None),
    ("POST", "/courses/{c}/settings", COURSE, {"turn_length_s": "60"}),
    ("POST", "/courses/{c}/members", COURSE, {"username": "student2"}),
    ("POST", "/courses/{c}/members/{s}/remove", COURSE, {}),
    ("POST", "/courses/{c}/members.csv", COURSE, {}),
    ("POST", "/users/{s}/reset-password", COURSE, {}),
    ("POST", "/invitations", COURSE, {"course_id": "{c}", "role": "student"}),
    ("GET", "/admin/users", ADMIN, None),
    ("POST", "/admin/users", ADMIN, {"username": "intruder", "role": "admin"}),
    ("POST", "/admin/users/{s}/active", ADMIN, {"active": "0"}),
    ("POST", "/admin/users/{s}/role", ADMIN, {"role": "admin"}),
    ("GET", "/admin/robots", ADMIN, None),
    ("POST", "/admin/robots", ADMIN, {"name": "evil", "address": "127.0.0.1:1"}),
    ("POST", "/admin/robots/{r}", ADMIN, {"enabled": "0"}),
    ("GET", "/admin/invitations", ADMIN, None),
    ("POST", "/invitations/{i}/revoke", COURSE, {"back": "/lab"}),
    ("GET", "/account/password", ALL, None),
    ("POST", "/account/password", ALL, {"current_password": "x", "new_password": "y", "new_password_again": "y"}),
]
APIS = [
    ("GET", "/api/courses", ALL, None),
    ("POST", "/api/courses", TEACHERS, {"code": "NEW2", "title": "New"}),
    ("GET", "/api/courses/{c}", COURSE, None),
    ("PATCH", "/api/courses/{c}", COURSE, {"turn_length_s": 60}),
    ("POST", "/api/courses/{c}/members", COURSE, {"username": "student2"}),
    ("DELETE", "/api/courses/{c}/members/{s}", COURSE, None),
    ("POST", "/api/courses/{c}/members.csv", COURSE, {}),
    ("POST", "/api/invitations", COURSE, {"course_id": "{c}", "role": "student"}),
    ("DELETE", "/api/invitations/{i}", COURSE, None),
    ("GET", "/api/users", ADMIN, None),
    ("POST", "/api/users", ADMIN, {"username": "intruder", "role": "admin"}),
    ("PATCH", "/api/users/{s}", ADMIN, {"role": "admin", "is_active": False}),
    ("POST", "/api/users/{s}/password-reset", COURSE, None),
    ("GET", "/api/admin/robots", ADMIN, None),
    ("POST", "/api/admin/robots", ADMIN, {"name": "evil", "address": "127.0.0.1:1"}),
    ("PATCH", "/api/admin/robots/{r}", ADMIN, {"enabled": False}),
    ("POST", "/api/account/password", ALL, {"current_password": "x", "new_password": "yyyyyyyyyyyy"}),
]


def _fill(value: object, ids: dict[str, int]) -> object:
    if isinstance(value, str):
        return value.format(**ids)
    if isinstance(value, dict):
        return {k: _fill(v, ids) for k, v in value.items()}
    return value


def _ids(app, course_people: dict[str, int]) -> dict[str, int]:
    from sqlalchemy import select

    from middleware.accounts.invitations import create_invitation
    from middleware.db import session_factory
    from middleware.models import Robot, User
    from middleware.robots.registry import robot_registry

    robot_registry(app).refresh()
    with session_factory(app)() as session:
        robot_id = session.scalar(select(Robot.id).where(Robot.name == "ghost"))
        tutor = session.get(User, course_people["tutor1"])
        invitation, _ = create_invitation(session, tutor, "student", course_people["course"], timedelta(days=1),
                                          datetime.now(UTC))
        session.commit()
        return {"c": course_people["course"], "s": course_people["student1"], "r": int(robot_id or 0),
                "i": invitation.id}


def _page(client: LabClient, method: str, path: str, form: dict[str, str] | None, logged_in: bool) -> int:
    if method == "GET":
        return client.request("GET", path)[0]
    token = client.csrf_token("/account/password" if logged_in else "/login")
    return client.request(method, path, {**(form or {}), "csrf_token": token})[0]


@pytest.mark.parametrize("who", [None, "student1", "student2", "tutor2", "tutor1"])
def test_forbidden_pages_and_api_calls_are_refused_and_change_nothing(app, client_as, course_people, snapshot,
                                                                       who: str | None) -> None:
    ids = _ids(app, course_people)
    client = client_as(who)
    before = snapshot()
    checked = 0
    for method, path, allowed, body in PAGES:
        if who in allowed:
            continue
        status = _page(client, method, _fill(path, ids), _fill(body, ids), who is not None)
        expected = 302 if who is None else 403
        assert status == expected, f"{who} {method} {path}: {status}"
        checked += 1
    for method, path, allowed, body in APIS:
        if who in allowed:
            continue
        status, answer = api(client, method, _fill(path, ids), _fill(body, ids))
        expected = 401 if who is None else 403
        assert status == expected, f"{who} {method} {path}: {status} {answer}"
        assert answer["error"]["code"] in ("not_logged_in", "forbidden")
        checked += 1
    assert checked > 0
    assert snapshot() == before


def test_admins_reach_every_page(client_as, course_people, app) -> None:
    ids = _ids(app, course_people)
    admin = client_as("admin1")
    for method, path, _allowed, _body in PAGES:
        if method == "GET":
            assert admin.request("GET", _fill(path, ids))[0] == 200, path


def test_unknown_objects_are_404(client_as, course_people) -> None:
    admin = client_as("admin1")
    assert admin.request("GET", "/courses/999999")[0] == 404
    assert api(admin, "GET", "/api/courses/999999")[0] == 404
    assert api(admin, "POST", "/api/users/999999/password-reset")[0] == 404
    assert api(admin, "PATCH", "/api/admin/robots/999999", {"enabled": False})[0] == 404


def test_a_tutor_resets_a_students_password_once_and_the_student_logs_in_with_it(client_as, course_people) -> None:
    tutor = client_as("tutor1")
    status, answer = api(tutor, "POST", f"/api/users/{course_people['student1']}/password-reset")
    assert status == 200 and answer["username"] == "student1"
    fresh = client_as(None)
    assert fresh.login("student1", answer["password"]) == 302


def test_a_disabled_account_is_logged_out_at_its_next_request(client_as, course_people) -> None:
    student = client_as("student2")
    assert student.request("GET", "/lab")[0] == 200
    admin = client_as("admin1")
    status, _ = api(admin, "PATCH", f"/api/users/{course_people['student2']}", {"is_active": False})
    assert status == 200
    status, headers, _ = student.request("GET", "/lab")
    assert status == 302 and "/login" in headers["Location"]
    assert api(student, "GET", "/api/courses")[0] == 401
    assert client_as(None).login("student2", "correct-horse-battery") == 401


def test_login_is_slowed_per_account_and_address_over_http(client_as, course_people, monkeypatch) -> None:
    from datetime import timedelta

    from middleware.auth import throttle

    # A first delay of a minute, so that a loaded machine cannot outwait it between two requests.
    monkeypatch.setattr(throttle, "PER_ACCOUNT_AND_ADDRESS",
                        throttle.DelayRule(3, timedelta(minutes=1), timedelta(minutes=15)))
    client = client_as(None)
    for _ in range(3):
        assert client.login("student2", "wrong-password-x") == 401
    token = client.csrf_token()
    status, headers, body = client.request("POST", "/login", {
        "username": "student2", "password": "correct-horse-battery", "csrf_token": token})
    assert status == 429 and "Too many failed attempts from here; try again in" in body
    assert 1 <= int(headers["Retry-After"]) <= 60


def test_own_password_change_through_the_api(client_as, course_people) -> None:
    student = client_as("student1")
    status, answer = api(student, "POST", "/api/account/password",
                         {"current_password": "wrong-one", "new_password": "another-long-secret"})
    assert status == 400 and answer["error"]["field"] == "current_password"
    status, _ = api(student, "POST", "/api/account/password",
                    {"current_password": "correct-horse-battery", "new_password": "another-long-secret"})
    assert status == 200
    assert client_as(None).login("student1", "another-long-secret") == 302


