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


def test_the_session_is_renewed_every_few_minutes_not_on_every_request(student_client: LabClient,
                                                                        monkeypatch) -> None:
    from middleware.auth import routes

    _, headers, _ = student_client.request("GET", "/api/robots/lab-1")
    assert "Set-Cookie" not in headers, "a fresh session is not re-signed on each request"
    monkeypatch.setattr(routes, "SESSION_RENEW_S", 0)
    _, headers, _ = student_client.request("GET", "/api/robots/lab-1")
    assert "Expires=" in headers.get("Set-Cookie", ""), "an old one is renewed: the expiry slides"
    status, _, _ = student_client.request("GET", "/api/robots/lab-1")
    assert status == 200


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


def test_a_deactivated_account_is_refused_at_once_here_and_within_max_age_from_another_process(
    student_client: LabClient, live_server, monkeypatch
) -> None:
    from sqlalchemy import select, text

    from middleware.auth import identity
    from middleware.db import session_factory
    from middleware.models import User

    assert student_client.request("GET", "/api/robots/lab-1")[0] == 200  # the user's copy is now kept
    with session_factory(live_server.app)() as session:
        user_id = session.scalar(select(User.id).where(User.username == "student1"))
        # Another web process deactivates the account: plain SQL, no ORM event reaches this process.
        session.execute(text("UPDATE users SET is_active = :off WHERE id = :id"), {"off": False, "id": user_id})
        session.commit()
    assert student_client.request("GET", "/api/robots/lab-1")[0] == 200, "within MAX_AGE_S the copy stands"
    monkeypatch.setattr(identity, "MAX_AGE_S", 0.0)
    assert student_client.request("GET", "/api/robots/lab-1")[0] == 401
    monkeypatch.undo()
    with session_factory(live_server.app)() as session:
        session.execute(text("UPDATE users SET is_active = :on WHERE id = :id"), {"on": True, "id": user_id})
        session.commit()
    identity.forget(user_id)
    assert student_client.request("GET", "/api/robots/lab-1")[0] == 200
    with session_factory(live_server.app)() as session:  # through the ORM in this process: refused at once
        session.get(User, user_id).is_active = False
        session.commit()
    assert student_client.request("GET", "/api/robots/lab-1")[0] == 401


def test_changing_a_password_ends_the_accounts_other_sessions_but_not_this_one(live_server) -> None:
    from tests.integration.lab.test_skills_api import api

    here, elsewhere = LabClient(live_server.url), LabClient(live_server.url)
    assert here.login() == 302 and elsewhere.login() == 302
    assert elsewhere.request("GET", "/api/robots/lab-1")[0] == 200
    status, body = api(here, "POST", "/api/account/password",
                       {"current_password": STUDENT_PASSWORD, "new_password": "a-brand-new-passphrase"})
    assert status == 200, body
    assert here.request("GET", "/api/robots/lab-1")[0] == 200, "the session that changed it stays"
    assert elsewhere.request("GET", "/api/robots/lab-1")[0] == 401, "the other one ends"
    again = LabClient(live_server.url)
    assert again.login(password="a-brand-new-passphrase") == 302
    assert again.request("GET", "/api/robots/lab-1")[0] == 200
    status, body = api(here, "POST", "/api/account/password",
                       {"current_password": "a-brand-new-passphrase", "new_password": STUDENT_PASSWORD})
    assert status == 200, body
