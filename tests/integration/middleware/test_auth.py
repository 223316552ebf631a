"""Logging in and out through the real server: CSRF, clear messages, protected pages."""

from __future__ import annotations

import json

from tests.conftest import STUDENT_PASSWORD, LabClient


def test_the_student_logs_in_and_reaches_the_lab(lab_client: LabClient) -> None:
    token = lab_client.csrf_token()
    status, headers, _ = lab_client.request(
        "POST", "/login", {"username": "student1", "password": STUDENT_PASSWORD, "csrf_token": token}
    )
    assert status == 302 and headers["Location"].endswith("/lab")
    status, _, body = lab_client.request("GET", "/lab")
    assert status == 200 and "lab-1" in body


def test_a_wrong_password_says_so_and_logs_nobody_in(lab_client: LabClient) -> None:
    token = lab_client.csrf_token()
    status, _, body = lab_client.request(
        "POST", "/login", {"username": "student1", "password": "not-the-password", "csrf_token": token}
    )
    assert status == 401 and "Wrong username or password" in body
    assert lab_client.request("GET", "/lab")[0] == 302


def test_login_without_a_csrf_token_is_refused_with_a_sentence(lab_client: LabClient) -> None:
    status, _, body = lab_client.request("POST", "/login", {"username": "student1", "password": STUDENT_PASSWORD})
    assert status == 400 and "security token" in body
    assert lab_client.request("GET", "/lab")[0] == 302


def test_pages_and_api_require_a_login(lab_client: LabClient) -> None:
    status, headers, _ = lab_client.request("GET", "/lab/lab-1")
    assert status == 302 and "/login?next=" in headers["Location"]
    status, _, body = lab_client.request("GET", "/api/robots/lab-1")
    assert status == 401 and json.loads(body)["error"]["code"] == "not_logged_in"


def test_logout_needs_the_csrf_token_and_ends_the_session(student_client: LabClient) -> None:
    assert student_client.request("POST", "/logout", {})[0] == 400
    assert student_client.request("GET", "/lab")[0] == 200
    token = student_client.csrf_token("/lab")
    assert student_client.request("POST", "/logout", {"csrf_token": token})[0] == 302
    assert student_client.request("GET", "/lab")[0] == 302


def test_an_open_redirect_through_next_is_ignored(lab_client: LabClient) -> None:
    token = lab_client.csrf_token()
    status, headers, _ = lab_client.request("POST", "/login", {
        "username": "student1", "password": STUDENT_PASSWORD, "csrf_token": token, "next": "//evil.example/x",
    })
    assert status == 302 and headers["Location"].endswith("/lab")


def test_the_session_cookie_is_httponly_and_samesite(lab_client: LabClient) -> None:
    token = lab_client.csrf_token()
    _, headers, _ = lab_client.request("POST", "/login", {
        "username": "student1", "password": STUDENT_PASSWORD, "csrf_token": token,
    })
    cookie = headers["Set-Cookie"]
    assert "HttpOnly" in cookie and "SameSite=Lax" in cookie


def test_the_robot_api_describes_robots_and_names_unknown_ones(student_client: LabClient) -> None:
    status, _, body = student_client.request("GET", "/api/robots/lab-1")
    description = json.loads(body)
    assert status == 200 and description["online"] is True
    assert description["info"]["max_linear_mps"] > 0 and description["info"]["camera_width_px"] == 320
    status, _, body = student_client.request("GET", "/api/robots/nope")
    assert status == 404 and json.loads(body)["error"] == {
        "code": "unknown_robot", "message": "There is no robot named 'nope'.", "field": "robot_name",
    }
    status, _, body = student_client.request("GET", "/api/robots/ghost")
    assert status == 200 and json.loads(body) == {"name": "ghost", "title": "Ghost", "online": False, "info": None}
