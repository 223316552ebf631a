"""The request's unit of work (middleware/db.py) and the one Refused handler (middleware/errors.py), on test-only
views: a view that flushed and then failed leaves nothing behind, whatever answers the failure; a view that
returned (a redirect too) commits; a Refused is JSON under /api/ and the sentence on a page."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from flask import Flask, redirect
from sqlalchemy import func, select

from tests.conftest import _let_go, make_test_app


@pytest.fixture
def uow_app(database_url: str, tmp_path: Path) -> Iterator[Flask]:
    """The app (no robot answers) with views that write a preference, then succeed or fail in each way."""
    from middleware.db import after_commit, get_session, session_factory
    from middleware.errors import Refused, unless_refused
    from middleware.models import User, UserPreference

    app = make_test_app(database_url, "ghost=127.0.0.1:9", tmp_path)
    app.config["AFTER_COMMIT_RAN"] = []

    def write(key: str) -> None:
        session = get_session()
        user = session.scalar(select(User).where(User.username == "student1"))
        session.add(UserPreference(user_id=user.id, key=key, value_json="1"))
        session.flush()  # what a service does: the row is in the transaction, not committed
        after_commit(lambda: app.config["AFTER_COMMIT_RAN"].append(key))

    def refused() -> Refused:
        return Refused(409, "test_refused", "Do the other thing first.", "the_field")

    def crash() -> str:
        write("crash")
        raise RuntimeError("a bug after the flush")

    def refuse() -> str:
        write("refuse")
        raise refused()

    def form() -> object:
        def act() -> object:
            write("form")
            raise refused()

        return unless_refused(act, lambda error: (f"<p>{error.message}</p>", error.status))

    def redirected() -> object:
        write("redirected")
        return redirect("/elsewhere", 303)

    for rule, view in (("/api/test/crash", crash), ("/test/crash", crash), ("/api/test/refuse", refuse),
                       ("/test/refuse", refuse), ("/test/form", form), ("/test/redirected", redirected)):
        app.add_url_rule(rule, endpoint=rule, view_func=view)
    yield app
    _let_go(app)  # its ticker, links, farm and practice keeper
    session_factory(app).kw["bind"].dispose()  # before the PostgreSQL database is dropped


def stored_keys(app: Flask) -> list[str]:
    from middleware.db import session_factory
    from middleware.models import UserPreference

    with session_factory(app)() as session:
        return sorted(session.scalars(select(UserPreference.key)))


@pytest.mark.parametrize(("path", "status"), [("/api/test/crash", 500), ("/test/crash", 500),
                                              ("/api/test/refuse", 409), ("/test/refuse", 409), ("/test/form", 409)])
def test_a_view_failing_after_a_flush_leaves_nothing_in_the_database(uow_app: Flask, path: str, status: int) -> None:
    assert uow_app.test_client().get(path).status_code == status
    assert stored_keys(uow_app) == []
    assert uow_app.config["AFTER_COMMIT_RAN"] == []


def test_a_view_that_redirects_commits_once_and_then_runs_its_after_commit_work(uow_app: Flask) -> None:
    answer = uow_app.test_client().get("/test/redirected")
    assert answer.status_code == 303
    assert stored_keys(uow_app) == ["redirected"]
    assert uow_app.config["AFTER_COMMIT_RAN"] == ["redirected"]


def test_an_api_refusal_is_json_with_its_code_and_field_and_on_a_page_the_sentence(uow_app: Flask) -> None:
    client = uow_app.test_client()
    api = client.get("/api/test/refuse")
    assert api.status_code == 409 and api.is_json
    assert api.get_json() == {"error": {"code": "test_refused", "message": "Do the other thing first.",
                                        "field": "the_field"}}
    page = client.get("/test/refuse")
    assert page.status_code == 409 and page.mimetype == "text/html"
    body = page.get_data(as_text=True)
    assert '<p id="error-message">Do the other thing first.</p>' in body
    assert "test_refused" not in body and "the_field" not in body


def test_work_outside_a_request_commits_its_block_or_nothing(uow_app: Flask) -> None:
    from middleware.db import unit_of_work
    from middleware.models import User, UserPreference

    with pytest.raises(RuntimeError), unit_of_work(uow_app) as session:
        user_id = session.scalar(select(User.id).where(User.username == "student1"))
        session.add(UserPreference(user_id=user_id, key="thread", value_json="1"))
        session.flush()
        raise RuntimeError("the socket's message failed")
    assert stored_keys(uow_app) == []
    with unit_of_work(uow_app) as session:
        session.add(UserPreference(user_id=user_id, key="thread", value_json="1"))
    with unit_of_work(uow_app) as session:
        assert session.scalar(select(func.count()).select_from(UserPreference)) == 1
