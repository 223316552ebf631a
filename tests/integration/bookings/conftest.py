"""Accounts in courses on the live app, and clients logged in as each role."""

from __future__ import annotations

import json
from collections.abc import Callable
from urllib.request import HTTPCookieProcessor, Request, build_opener

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, add_test_account

ROLES = {"student1": "student", "student2": "student", "tutor1": "tutor", "tutor2": "tutor", "admin1": "admin"}


@pytest.fixture
def course_people(app) -> dict[str, int]:
    """student1 and student2 in course ROB1 (tutor1), tutor2 tutoring ROB2, and admin1; name -> id."""
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User

    with session_factory(app)() as session:
        for name, role in ROLES.items():
            if name != "student1":
                add_test_account(session, name, role)
        course = Course(code="ROB1", title="Robotics 1", booking_allowance_min=120)
        other = Course(code="ROB2", title="Robotics 2", booking_allowance_min=60)
        session.add_all([course, other])
        session.flush()
        ids = {name: session.scalar(select(User.id).where(User.username == name)) for name in ROLES}
        for name, course_id, role in [("student1", course.id, "student"), ("student2", course.id, "student"),
                                      ("tutor1", course.id, "tutor"), ("tutor2", other.id, "tutor")]:
            session.add(CourseMembership(course_id=course_id, user_id=ids[name], role=role))
        session.commit()
        ids["course"], ids["other_course"] = course.id, other.id
    return ids


@pytest.fixture
def client_as(live_server: LiveServer, course_people) -> Callable[[str | None], LabClient]:
    """A client logged in as the named account (None: anonymous)."""

    def make(username: str | None) -> LabClient:
        client = LabClient(live_server.url)
        if username is not None:
            assert client.login(username, STUDENT_PASSWORD) == 302
        return client

    return make


def api(client: LabClient, method: str, path: str, body: object = None,
        extra_headers: dict[str, str] | None = None) -> tuple[int, dict]:
    """A JSON request carrying the session, a CSRF token and extra_headers (Accept-Language); (status, body)."""
    headers = {"Accept": "application/json", **(extra_headers or {})}
    if method not in ("GET", "HEAD"):
        status, _, _ = client.request("GET", "/login")
        headers["X-CSRFToken"] = client.csrf_token("/login" if status == 200 else "/bookings?tz=UTC")
    data = None
    if body is not None:
        data = json.dumps(body).encode()
        headers["Content-Type"] = "application/json"
    opener = build_opener(HTTPCookieProcessor(client.cookies))
    try:
        with opener.open(Request(client.base_url + path, data=data, method=method, headers=headers),
                         timeout=10) as response:
            return response.status, json.loads(response.read() or b"{}")
    except Exception as error:
        if hasattr(error, "code"):
            return error.code, json.loads(error.read() or b"{}")
        raise
