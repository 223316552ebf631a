"""xAPI statements reach a Learning Record Store through the durable outbox: queued once, sent with the xAPI
headers, retried after a failure, and sent by another process after a restart (nothing lost), on SQLite and
PostgreSQL. The LRS is a stand-in: a real little HTTP server on 127.0.0.1 started by the test, answering as the
xAPI 1.0.3 statement resource does (204 to a PUT), with the failures the test asks of it."""

from __future__ import annotations

import base64
import json
import threading
from collections.abc import Iterator
from datetime import timedelta
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, urlsplit

import pytest

from tests.conftest import make_test_app
from tests.integration.analytics.conftest import at, history


class LrsStandIn:
    """An LRS stand-in: records every PUT /xapi/statements; answers the statuses queued in `answers`, then 204."""

    def __init__(self) -> None:
        self.received: list[dict[str, object]] = []
        self.answers: list[int] = []
        self.refuse_ids: set[str] = set()
        self.heard = threading.Event()
        stand_in = self

        class Handler(BaseHTTPRequestHandler):
            def do_PUT(self) -> None:  # noqa: N802 - http.server's name
                parts = urlsplit(self.path)
                body = self.rfile.read(int(self.headers.get("Content-Length", "0")))
                statement_id = parse_qs(parts.query).get("statementId", [""])[0]
                stand_in.received.append({"path": parts.path, "statement_id": statement_id,
                                          "version": self.headers.get("X-Experience-API-Version"),
                                          "auth": self.headers.get("Authorization"),
                                          "type": self.headers.get("Content-Type"), "body": json.loads(body)})
                status = 400 if statement_id in stand_in.refuse_ids else (
                    stand_in.answers.pop(0) if stand_in.answers else 204)
                self.send_response(status)
                self.send_header("Content-Length", "0")
                self.end_headers()
                stand_in.heard.set()

            def log_message(self, *_args: object) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_port}/xapi/"
        self._thread = threading.Thread(target=self.server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def lrs() -> Iterator[LrsStandIn]:
    stand_in = LrsStandIn()
    yield stand_in
    stand_in.close()


def configured(app, lrs: LrsStandIn) -> None:
    app.config.update(XAPI_LRS_URL=lrs.url, XAPI_HOMEPAGE="https://telelab.example.edu", XAPI_LRS_USERNAME="key",
                      XAPI_LRS_PASSWORD="secret", XAPI_SEND_INTERVAL_S="0.05")


def statuses(app) -> dict[str, int]:
    from sqlalchemy import func, select

    from middleware.db import session_factory
    from middleware.models.analytics import XapiStatement

    with session_factory(app)() as session:
        return dict(session.execute(select(XapiStatement.status, func.count()).group_by(XapiStatement.status)).all())


def test_statements_are_sent_once_retried_after_a_failure_and_sent_after_a_restart(database_url, tmp_path, lrs) -> None:
    from middleware import create_app
    from middleware.analytics import analytics_of
    from middleware.analytics.xapi_schema import statement_errors
    from tests.conftest import _let_go

    app = make_test_app(database_url, "lab-1=127.0.0.1:9", tmp_path / "one")
    history(app)
    configured(app, lrs)
    sender = analytics_of(app).sender
    lrs.answers = [503]  # the LRS is away for the first statement
    now = at(9, 0)  # a week after the history began: its last seven days are queued
    # Queued: 2 learning events, 2 tests, 1 exercise, 4 sessions that ended after 2 March 00:00 UTC.
    assert sender.run_once(now) == (8, 1)
    assert statuses(app) == {"sent": 8, "pending": 1}
    assert len(lrs.received) == 9
    for request in lrs.received:
        assert request["path"] == "/xapi/statements" and request["version"] == "1.0.3"
        assert request["type"] == "application/json"
        assert request["auth"] == "Basic " + base64.b64encode(b"key:secret").decode()
        body = request["body"]
        assert isinstance(body, dict) and body["id"] == request["statement_id"] and statement_errors(body) == []
        assert body["object"]["id"].startswith("https://telelab.example.edu/")
    missed = lrs.received[0]["statement_id"]
    sender.stop()
    _let_go(app)

    # Another process (a restart) on the same database: it sends what was left once the backoff has passed.
    again = create_app({"DATABASE_URL": database_url, "SECRET_KEY": "x" * 32, "TESTING": True, "ROBOTS": {}})
    again.instance_path = str(tmp_path / "two")
    configured(again, lrs)
    sender = analytics_of(again).sender
    assert sender.run_once(now + timedelta(seconds=5)) == (0, 0), "not before its backoff"
    assert sender.run_once(now + timedelta(minutes=10)) == (1, 0)
    assert statuses(again) == {"sent": 9}
    assert [r["statement_id"] for r in lrs.received].count(missed) == 2
    assert len({r["statement_id"] for r in lrs.received}) == 9 and len(lrs.received) == 10
    assert sender.run_once(now + timedelta(minutes=20)) == (0, 0), "nothing is queued twice"
    assert len(lrs.received) == 10

    # An LRS that refuses a statement for good (400) marks it failed with its answer; nothing else is touched.
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.analytics import LearningEvent, XapiStatement

    with session_factory(again)() as session:
        s1 = session.query(User).filter_by(username="s1").one()
        event = LearningEvent(user_id=s1.id, kind="lesson_watched", object_id=1, at=now + timedelta(minutes=25))
        session.add(event)
        session.commit()
        from middleware.analytics.statements import StatementBuilder
        lrs.refuse_ids.add(StatementBuilder(session, "https://telelab.example.edu").statement_id(
            "lesson_watched", event.id))
    assert sender.run_once(now + timedelta(minutes=30)) == (0, 1)
    with session_factory(again)() as session:
        refused = session.query(XapiStatement).filter_by(status="failed").one()
        assert refused.last_error is not None and "400" in refused.last_error and refused.tries == 1

    # A deleted account's statements go with it, waiting or sent: none is sent after.
    lrs.answers = [503]
    with session_factory(again)() as session:
        s2 = session.query(User).filter_by(username="s2").one()
        session.add(LearningEvent(user_id=s2.id, kind="tour_followed", object_id=1, at=now + timedelta(minutes=35)))
        session.commit()
    assert sender.run_once(now + timedelta(minutes=40)) == (0, 1)
    with session_factory(again)() as session:
        session.delete(session.query(User).filter_by(username="s2").one())
        session.commit()
        assert session.query(XapiStatement).filter_by(user_id=s2.id).count() == 0
    heard = len(lrs.received)
    assert sender.run_once(now + timedelta(hours=2)) == (0, 0) and len(lrs.received) == heard
    sender.stop()
    _let_go(again)


def test_the_sender_thread_sends_a_new_statement_within_its_interval(tmp_path, lrs) -> None:
    from middleware.analytics import analytics_of
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.accounts import utc_now
    from middleware.models.analytics import LearningEvent
    from tests.conftest import _let_go

    app = make_test_app(f"sqlite:///{tmp_path / 'lrs.sqlite3'}", "lab-1=127.0.0.1:9", tmp_path)
    configured(app, lrs)
    with session_factory(app)() as session:
        student = session.query(User).filter_by(username="student1").one()
        session.add(LearningEvent(user_id=student.id, kind="tour_followed", object_id=7, at=utc_now()))
        session.commit()
    assert app.test_client().get("/login").status_code == 200  # the first request starts the sender
    lrs.heard.wait(10)
    analytics_of(app).sender.stop()
    _let_go(app)
    assert [r["body"]["verb"]["display"]["en"] for r in lrs.received] == ["completed"]


def test_two_processes_sending_at_once_send_each_statement_once(database_url, tmp_path, lrs) -> None:
    """Two web processes (two apps on one database) queue and send at the same moment, as a former leader and the
    new one may for one pass: every statement reaches the LRS once, and both passes end without an error."""
    from middleware import create_app
    from middleware.analytics import analytics_of
    from tests.conftest import _let_go

    first = make_test_app(database_url, "lab-1=127.0.0.1:9", tmp_path / "one")
    history(first)
    second = create_app({"DATABASE_URL": database_url, "SECRET_KEY": "y" * 32, "TESTING": True, "ROBOTS": {}})
    second.instance_path = str(tmp_path / "two")
    apps = [first, second]
    for app in apps:
        configured(app, lrs)
    start = threading.Barrier(2)
    outcomes: list[object] = []

    def run(app) -> None:
        start.wait(10)
        try:
            outcomes.append(analytics_of(app).sender.run_once(at(9, 0)))
        except Exception as error:  # noqa: BLE001 - the test reports it below
            outcomes.append(error)

    threads = [threading.Thread(target=run, args=(app,)) for app in apps]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    for app in apps:
        analytics_of(app).sender.stop()
        _let_go(app)
    assert all(isinstance(o, tuple) for o in outcomes) and len(outcomes) == 2, outcomes
    assert sum(sent for sent, _missed in outcomes) == 9  # type: ignore[misc]
    ids = [r["statement_id"] for r in lrs.received]
    assert len(ids) == len(set(ids)) == 9, ids
    assert statuses(first) == {"sent": 9}
