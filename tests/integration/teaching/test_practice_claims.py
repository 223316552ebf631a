"""A practice robot is claimed in the request's unit of work and started by the farm once that is committed: ten
students claiming at once each get their own robot (a double click gets one), a claim rolled back starts nothing,
and a claim whose start died with its process is released by the keeper or replaced by its owner's next start; on
SQLite and PostgreSQL, with real robots."""

from __future__ import annotations

import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from datetime import timedelta
from pathlib import Path

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, add_test_account, make_test_app
from tests.integration.teaching.test_practice_console_and_uploads import _api

STUDENTS = [f"p{i:02}" for i in range(1, 11)]


@pytest.fixture
def practice_lab(database_url: str, tmp_path: Path, skill_server_address: str) -> Iterator[LiveServer]:
    """The app with ten students, served."""
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager
    from tests.conftest import _let_go

    app = make_test_app(database_url, f"lab-1={skill_server_address}", tmp_path)
    with session_factory(app)() as session:
        for name in STUDENTS:
            add_test_account(session, name, "student")
        session.commit()
    server = LiveServer(app)
    try:
        yield server
    finally:
        practice_manager(app).shutdown()
        server.stop()
        _let_go(app)
        session_factory(app).kw["bind"].dispose()


def _login(server: LiveServer, name: str) -> LabClient:
    client = LabClient(server.url)
    assert client.login(name, STUDENT_PASSWORD) == 302
    return client


def test_ten_students_claiming_at_once_each_get_their_own_robot_once_the_claims_are_committed(practice_lab) -> None:
    from middleware.farm.setup import robot_farm
    from middleware.teaching.practice_robots import practice_manager

    clients = [_login(practice_lab, name) for name in STUDENTS]
    double = _login(practice_lab, STUDENTS[0])  # the first student's second tab, clicking at the same moment
    with ThreadPoolExecutor(len(clients) + 1) as pool:
        answers = list(pool.map(lambda client: _api(client, "POST", "/api/practice"), [*clients, double]))
    for status, body in answers[:-1]:
        assert status in (200, 202), body  # 200: the other tab's start of the same robot answered first
    status, body = answers[-1]
    assert (status == 503 and body["error"]["code"] == "practice_start_failed") or status in (200, 202), body
    assert sum(1 for status, body in answers[:1] + answers[-1:] if status == 202) >= 1
    for name, client in zip(STUDENTS, clients, strict=True):
        status, seen = _api(client, "GET", "/api/practice")
        assert status == 200 and seen["running"] and not seen["starting"], seen
        assert seen["name"] == f"practice-{name}" and seen["console_url"] == f"/lab/practice-{name}"
        status, ran = _api(client, "POST", "/api/practice/commands", {"command": {"stop": True}})
        assert status == 202 and ran["robot"] == f"practice-{name}", ran
    farm = robot_farm(practice_lab.app)
    assert sorted(robot.name for robot in farm.robots()) == [f"practice-{name}" for name in STUDENTS]
    assert len({robot.address for robot in farm.robots()}) == len(STUDENTS)
    assert practice_manager(practice_lab.app).count() == len(STUDENTS)
    status, again = _api(clients[1], "POST", "/api/practice")
    assert status == 200 and again["running"] and again["name"] == f"practice-{STUDENTS[1]}"
    status, stopped = _api(clients[1], "DELETE", "/api/practice")
    assert status == 200 and stopped["stopped"] and not stopped["running"], stopped
    assert farm.find(f"practice-{STUDENTS[1]}") is None
    assert _api(clients[1], "GET", "/api/practice")[1]["running"] is False


def test_a_claim_starts_nothing_before_its_commit_and_nothing_at_all_when_rolled_back(practice_lab) -> None:
    from middleware.db import session_factory
    from middleware.farm.setup import robot_farm
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager

    app = practice_lab.app
    manager, farm, sessions = practice_manager(app), robot_farm(app), session_factory(app)
    with sessions() as session:
        user_id = session.query(User.id).filter(User.username == "p01").scalar()
    with sessions() as session:
        pending = manager.begin_start(session, user_id, "p01")
        assert pending is not None and pending.name == "practice-p01"
        assert farm.find("practice-p01") is None and manager.count() == 0  # claimed, not committed, not started
        session.rollback()
    assert manager.count() == 0 and manager.get(user_id) is None and not manager.starting(user_id)
    with sessions() as session, session.begin():
        pending = manager.begin_start(session, user_id, "p01")
    assert pending is not None and manager.starting(user_id) and farm.find("practice-p01") is None
    robot = pending.run()
    assert robot.name == "practice-p01" and robot.link.is_online() and manager.get(user_id) is not None


def test_a_second_claim_meeting_the_first_committed_meanwhile_is_told_it_is_starting_and_keeps_its_unit_of_work(
        practice_lab) -> None:
    """The race of the owner's two tabs (or a plan run beside a start): the second claim read no row, the first's
    being uncommitted, and its insert meets that row committed meanwhile. It answered 503 "starting already"
    (the ten students' test saw it on PostgreSQL when the second tab's claim came first); it is starting."""
    from sqlalchemy import event, select

    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager

    manager, sessions = practice_manager(practice_lab.app), session_factory(practice_lab.app)
    with sessions() as session:
        user_id = session.query(User.id).filter(User.username == "p04").scalar()
    def commit_before_insert(first, inserting: bool = True) -> None:
        if inserting and first.in_transaction():
            first.commit()  # the first claim is committed as the second one inserts (a statement, or a flush)

    def second_claim(first) -> tuple[object, str | None]:  # another request's thread (SQLite: its own connection)
        with sessions() as second:
            event.listen(second, "do_orm_execute", lambda state: commit_before_insert(first, state.is_insert))
            event.listen(second, "before_flush", lambda *_: commit_before_insert(first))
            pending = manager.begin_start(second, user_id, "p04")
            username = second.scalar(select(User.username).where(User.id == user_id))  # its unit of work goes on
            second.commit()
            return pending, username

    with sessions() as first, ThreadPoolExecutor(1) as pool:
        assert manager.begin_start(first, user_id, "p04") is not None  # flushed, not committed
        assert pool.submit(second_claim, first).result() == (None, "p04")  # the first one's start is under way
    assert manager.starting(user_id) and manager.count() == 1


def test_a_claim_whose_start_died_is_released_by_the_keeper_or_replaced_by_its_owner(practice_lab) -> None:
    from middleware.db import session_factory
    from middleware.farm.setup import robot_farm
    from middleware.models import User
    from middleware.teaching.practice_robots import PracticeManager, PracticeStartFailed

    app = practice_lab.app
    sessions = session_factory(app)
    farm = robot_farm(app)
    with sessions() as session:
        ann, bob = (session.query(User.id).filter(User.username == name).scalar() for name in ("p01", "p02"))
    manager = PracticeManager(farm, sessions, idle_s=2.0, start_deadline_s=1.5)  # the keeper looks every 0.5 s
    try:
        for user_id, name in ((ann, "p01"), (bob, "p02")):
            with sessions() as session, session.begin():
                assert manager.begin_start(session, user_id, name) is not None  # the process dies before run()
        assert manager.starting(ann) and manager.count() == 2
        with pytest.raises(PracticeStartFailed, match="starting already"):
            manager.start(ann, "p01")  # within the deadline the start may still come
        time.sleep(1.6)
        robot = manager.start(ann, "p01")  # past it, the owner's next start replaces the dead claim
        assert robot.link.is_online() and manager.get(ann) is not None
        deadline = time.monotonic() + 5
        while manager.count() > 1:  # bob's is released by the keeper
            assert time.monotonic() < deadline, "the dead claim was never released"
            time.sleep(0.1)
        assert not manager.starting(bob) and manager.get(bob) is None and farm.find("practice-p02") is None
    finally:
        manager.shutdown()


@pytest.mark.postgres
def test_an_owner_replacing_a_dead_claim_while_the_keeper_releases_it_gets_a_new_claim(practice_lab) -> None:
    """The owner's start reads its dead claim; the keeper releases that claim and commits; the start's delete then
    finds no row. That is no error (it was an ORM delete expecting one row): the start claims anew."""
    from sqlalchemy import event

    from middleware.db import session_factory
    from middleware.farm.setup import robot_farm
    from middleware.models import User
    from middleware.teaching.practice_robots import PracticeManager

    if not practice_lab.app.config["DATABASE_URL"].startswith("postgresql"):
        pytest.skip("SQLite serialises the two writers: the keeper cannot commit inside the start's transaction")
    sessions = session_factory(practice_lab.app)
    keeper = PracticeManager(robot_farm(practice_lab.app), sessions, idle_s=600, start_deadline_s=0.2)
    with sessions() as session:
        owner = session.query(User.id).filter(User.username == "p04").scalar()
    try:
        with sessions() as session, session.begin():
            assert keeper.begin_start(session, owner, "p04") is not None  # its process dies before run()
        time.sleep(0.3)
        released: list[list[str]] = []

        def keeper_releases_meanwhile(_conn, _cursor, statement, *_args) -> None:
            if not released and statement.lstrip().startswith("SELECT") and "personal_robots" in statement:
                released.append(keeper.release_dead_starts())  # its own session, committed

        with sessions() as session, session.begin():
            event.listen(session.connection(), "after_cursor_execute", keeper_releases_meanwhile)
            assert keeper.begin_start(session, owner, "p04") is not None
        assert released == [["practice-p04"]]
        assert keeper.starting(owner)  # the new claim, committed
    finally:
        keeper.shutdown()


def test_a_claim_released_as_dead_while_its_start_was_under_way_leaves_no_robot(practice_lab) -> None:
    from middleware.db import session_factory
    from middleware.farm.setup import robot_farm
    from middleware.models import User
    from middleware.models.accounts import utc_now
    from middleware.teaching.practice_robots import PracticeManager, PracticeStartFailed

    app = practice_lab.app
    sessions, farm = session_factory(app), robot_farm(app)
    now = [utc_now()]
    manager = PracticeManager(farm, sessions, idle_s=600, start_deadline_s=60, clock=lambda: now[0])
    with sessions() as session:
        user_id = session.query(User.id).filter(User.username == "p03").scalar()
    try:
        with sessions() as session, session.begin():
            pending = manager.begin_start(session, user_id, "p03")
        now[0] += timedelta(seconds=61)
        assert manager.release_dead_starts() == ["practice-p03"]
        with pytest.raises(PracticeStartFailed, match="stopped while it started"):
            pending.run()  # the slow start finishes after its claim was released: nobody's robot
        assert farm.find("practice-p03") is None and manager.count() == 0
    finally:
        manager.shutdown()

