"""A lab seeded with the demo course, lessons and tours, and a Flask test client logged in for each role."""

from __future__ import annotations

import secrets
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import _let_go

ROLES = ("anonymous", "student", "tutor", "admin")
# Nothing listens on port 9: robot routes meet an unreachable robot, fast, as when a robot is down.
UNREACHABLE_ROBOTS = "lab-1=127.0.0.1:9,course-a=127.0.0.1:9"


def seeded_lab(database_url: str, tmp_path: Path):
    """The app on database_url, migrated, with the demo accounts, course, tests, tours and lesson; CSRF off so
    hostile bodies reach the views, no practice robots and no predictions (starting one would spawn a skill server)."""
    from middleware import create_app
    from middleware.config import parse_robots
    from middleware.lab_runner import ensure_demo_accounts, seed_demo_course
    from middleware.teaching.demo_content import seed_demo_content
    from tests.conftest import migrate_to_head

    migrate_to_head(database_url)
    app = create_app({
        "DATABASE_URL": database_url, "SECRET_KEY": secrets.token_hex(16), "ROBOTS": parse_robots(UNREACHABLE_ROBOTS),
        "TESTING": True, "WTF_CSRF_ENABLED": False, "PRACTICE_CAP": 0, "PREDICTION_CAP": 0,
        "ROBOT_RPC_TIMEOUT_S": 0.2,
    })
    app.instance_path = str(tmp_path / "instance")
    passwords = {name: password for name, _role, password in ensure_demo_accounts(app)}
    seed_demo_course(app)
    seed_demo_content(app, record_video=False)
    app.config["TEST_PASSWORDS"] = passwords
    return app


def stop_lab(app) -> None:
    """Stops the app's background work (the access ticker, robot channels) and closes its database connections."""
    from middleware.db import session_factory

    _let_go(app)  # its ticker, links, farm and practice keeper
    session_factory(app).kw["bind"].dispose()


def logged_in_client(app, role: str):
    """A test client: anonymous, or logged in as the demo account named as the role."""
    client = app.test_client()
    if role != "anonymous":
        answer = client.post("/login", data={"username": role, "password": app.config["TEST_PASSWORDS"][role]})
        assert answer.status_code == 302, f"{role} could not log in"
    return client


@pytest.fixture(scope="module")
def hostile_lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator:
    """One seeded SQLite lab shared by a module's hostile requests (they change little: they are refused)."""
    tmp_path = tmp_path_factory.mktemp("hostile")
    app = seeded_lab(f"sqlite:///{tmp_path / 'lab.sqlite3'}", tmp_path)
    yield app
    stop_lab(app)


@pytest.fixture(scope="module")
def role_clients(hostile_lab) -> dict:
    """A test client per role."""
    return {role: logged_in_client(hostile_lab, role) for role in ROLES}
