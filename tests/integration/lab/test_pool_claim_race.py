"""Many students claim the last free robot of a pool at the same instant, on SQLite and PostgreSQL: exactly one gets
it, every other is refused 409 pool_full, and a claim queues nobody (the free check and the taking are one step)."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest
from sqlalchemy import func, select

from tests.conftest import DATABASES, LabClient, LiveServer, _let_go, add_test_account, make_test_app
from tests.integration.lab.test_first_write_after_idle import send_json

STUDENTS = 12


@pytest.fixture(params=DATABASES)
def pool_lab(request, tmp_path, skill_server_address: str) -> Iterator[LiveServer]:
    from middleware.db import session_factory

    database_url = (f"sqlite:///{tmp_path / 'claims.sqlite3'}" if request.param == "sqlite"
                    else request.getfixturevalue("postgres_url"))
    # Both names lead to the session's one skill server: the test is about seats, not driving.
    app = make_test_app(database_url, f"sim-1={skill_server_address},sim-2={skill_server_address}", tmp_path)
    app.config["ACCESS_GRACE_S"] = 60.0
    with session_factory(app)() as session:
        for n in range(STUDENTS):
            add_test_account(session, f"claimer{n}", "student")
        session.commit()
    server = LiveServer(app)
    try:
        yield server
    finally:
        server.stop()
        _let_go(app)


def _client(lab: LiveServer, username: str) -> tuple[LabClient, str]:
    client = LabClient(lab.url)
    assert client.login(username) == 302
    return client, client.csrf_token("/lab")


def _claim(client: LabClient, token: str) -> tuple[int, dict]:
    return send_json(client, token, "POST", "/api/pools/sim/claim")


def test_of_many_students_claiming_the_last_robot_at_once_one_gets_it_and_nobody_is_queued(pool_lab) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.db import session_factory
    from middleware.models import PoolQueueEntry, QueueEntry, User

    first, first_token = _client(pool_lab, "student1")
    status, taken = _claim(first, first_token)
    assert status == 200 and taken["robot_name"] in ("sim-1", "sim-2")
    last_robot = ({"sim-1", "sim-2"} - {taken["robot_name"]}).pop()

    claimers = [_client(pool_lab, f"claimer{n}") for n in range(STUDENTS)]
    answers: list[tuple[int, dict]] = []
    start = threading.Barrier(STUDENTS)

    def claim(client: LabClient, token: str) -> None:
        start.wait()
        answers.append(_claim(client, token))

    threads = [threading.Thread(target=claim, args=pair) for pair in claimers]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(120)

    assert len(answers) == STUDENTS
    won = [body for status, body in answers if status == 200]
    refused = [body for status, body in answers if status != 200]
    assert len(won) == 1, answers
    assert won[0]["robot_name"] == last_robot and won[0]["position"] == 0
    assert {(status, body["error"]["code"]) for status, body in answers if status != 200} == {(409, "pool_full")}
    assert len(refused) == STUDENTS - 1
    with session_factory(pool_lab.app)() as session:
        assert session.scalar(select(func.count()).select_from(PoolQueueEntry)) == 0, "a claim queues nobody"
        seated = session.scalars(select(User.username).join(QueueEntry, QueueEntry.user_id == User.id)
                                 .where(QueueEntry.robot_name == last_robot)).all()
    assert len(seated) == 1 and seated[0].startswith("claimer")
    assert access_coordinator(pool_lab.app).snapshot(last_robot).waiting_ids == ()
