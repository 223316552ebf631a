"""Two web workers on one PostgreSQL database hear each other's changes through LISTEN/NOTIFY at once (nothing
polls the tables): a chat message posted or deleted through one reaches a socket on the other, a robot an admin
adds through one is in the other's lab, a delay a tutor sets through one is applied by the other's viewers; a
transaction that rolls back announces nothing. A class at once, on one worker and on two: joins and leaves in the
same second reach every page, twelve students posting at once each read all the messages live, and a console that
moves to the other worker mid-turn drives with its next command."""

from __future__ import annotations

import contextlib
import json
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, make_course, make_test_app
from tests.integration.bookings.conftest import api
from tests.integration.chat.test_chat import next_of

pytestmark = pytest.mark.alone


def test_a_message_posted_on_one_worker_reaches_a_socket_on_the_other_at_once(postgres_url: str, tmp_path: Path,
                                                                                skill_server_address: str) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.events import bus_of
    from middleware.experiment.delay import delay_book

    robots = f"lab-1={skill_server_address}"
    first = make_test_app(postgres_url, robots, tmp_path / "one")
    second = make_test_app_without_user(postgres_url, robots, tmp_path / "two")
    with session_factory(first)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        session.commit()
    servers = [LiveServer(first), LiveServer(second)]
    try:
        reader, writer = LabClient(servers[0].url), LabClient(servers[1].url)
        assert reader.login() == 302 and writer.login("tutor1", STUDENT_PASSWORD) == 302
        socket = reader.websocket("/ws/robots/lab-1/chat")
        assert next_of(socket, "history")["messages"] == []
        assert bus_of(session_factory(first).kw["bind"]).listening.wait(10), "the first worker listens"
        delays = []
        for body in ("one", "two", "three"):
            sent = time.monotonic()
            status, posted = api(writer, "POST", "/api/robots/lab-1/chat", {"body": body})
            assert status == 201, posted
            assert next_of(socket, "message", timeout_s=2.0)["message"]["body"] == body
            delays.append(time.monotonic() - sent)
        print(f"\nposted on one worker -> read on the other's socket: {[f'{d * 1000:.0f} ms' for d in delays]}")
        assert max(delays) < 0.4, "delivered by notification, not a poll"
        status, _ = api(writer, "DELETE", f"/api/robots/lab-1/chat/{posted['message']['id']}")
        assert status == 200
        assert next_of(socket, "deleted", timeout_s=2.0)["id"] == posted["message"]["id"]
        socket.close()

        with session_factory(first)() as session:
            create_user(session, "root", "admin", STUDENT_PASSWORD)
            session.commit()
        admin = LabClient(servers[1].url)
        assert admin.login("root", STUDENT_PASSWORD) == 302
        status, added = api(admin, "POST", "/api/admin/robots", {"name": "lab-9", "address": "127.0.0.1:9"})
        assert status == 201, added
        added_at = time.monotonic()
        while 'data-robot="lab-9"' not in reader.request("GET", "/lab")[2]:
            assert time.monotonic() - added_at < 1.0, "the other worker did not hear of the new robot"
            time.sleep(0.05)

        make_course(first, "EV1", {"tutor1": "tutor", "student1": "student"})
        book, student_id = delay_book(first), find_user_id(first, "student1")
        assert book.delay_of(student_id, "lab-1") == 0.0
        status, _ = api(writer, "PUT", "/api/experiment/delays/student1", {"delay_s": 2.5})
        assert status == 200
        set_at = time.monotonic()
        while book.delay_of(student_id, "lab-1") != 2.5:
            assert time.monotonic() - set_at < 1.0, "the first worker's viewers did not get the new delay"
            time.sleep(0.02)
    finally:
        for server in servers:
            server.stop()
        for app in (first, second):
            _let_go(app)  # its ticker, and a practice keeper that would query the dropped database after
            session_factory(app).kw["bind"].dispose()


def find_user_id(app, username: str) -> int:
    from middleware.auth.services import find_user
    from middleware.db import session_factory

    with session_factory(app)() as session:
        return find_user(session, username).id


def make_test_app_without_user(database_url: str, robots: str, tmp_path: Path):
    """A second worker: the same database (already migrated, its users made by the first)."""
    import secrets

    from middleware import create_app
    from middleware.config import parse_robots

    app = create_app({"DATABASE_URL": database_url, "SECRET_KEY": secrets.token_hex(16),
                      "ROBOTS": parse_robots(robots), "TESTING": True})
    app.instance_path = str(tmp_path / "instance")
    return app


def test_an_announcement_is_heard_after_commit_and_never_after_a_rollback(postgres_url: str) -> None:
    from sqlalchemy import create_engine
    from sqlalchemy.orm import Session

    from middleware import events

    engine = create_engine(postgres_url)
    heard: list[str | None] = []
    arrived = threading.Event()

    def hear(key: str | None) -> None:
        heard.append(key)
        arrived.set()

    bus = events.bus_of(engine)
    stop = events.listen(engine, "probe", hear)
    try:
        assert bus.listening.wait(10)
        with Session(engine) as session:
            events.announce(session, "probe", "rolled-back")
            session.rollback()
            events.announce(session, "probe", "kept")
            assert not arrived.wait(0.3), "nothing before the commit"
            session.commit()
        assert arrived.wait(2) and heard == ["kept"]
    finally:
        stop()
        bus.close()
        engine.dispose()


def test_who_follows_a_live_class_on_one_worker_is_listed_on_the_other(postgres_url: str, tmp_path: Path,
                                                                         skill_server_address: str) -> None:
    import json

    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models.teaching import GuidedSession, Tour
    from middleware.teaching.demo_content import DEMO_TOURS
    from tests.integration.chat.test_chat import next_of

    robots = f"lab-1={skill_server_address}"
    first = make_test_app(postgres_url, robots, tmp_path / "one")
    second = make_test_app_without_user(postgres_url, robots, tmp_path / "two")
    with session_factory(first)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        session.commit()
    course_id = make_course(first, "LIVE1", {"tutor1": "tutor", "student1": "student"})
    with session_factory(first)() as session, session.begin():
        tour = Tour(slug="live-tour", title="Live", steps_json=json.dumps(DEMO_TOURS[0]["steps"]))
        session.add(tour)
        session.flush()
        live = GuidedSession(tour_id=tour.id, robot_name="lab-1", tutor_id=find_user_id(first, "tutor1"),
                             course_id=course_id, step_index=0, control_user_id=find_user_id(first, "tutor1"),
                             version=1)
        session.add(live)
    servers = [LiveServer(first), LiveServer(second)]
    try:
        student, tutor = LabClient(servers[0].url), LabClient(servers[1].url)
        assert student.login() == 302 and tutor.login("tutor1", STUDENT_PASSWORD) == 302
        tutors_page = tutor.websocket(f"/ws/tour-sessions/{live.id}")
        assert next_of(tutors_page, "state")["participants"] == ["tutor1"]
        students_page = student.websocket(f"/ws/tour-sessions/{live.id}")
        deadline = time.monotonic() + 3.0
        while next_of(tutors_page, "state", timeout_s=3.0)["participants"] != ["student1", "tutor1"]:
            assert time.monotonic() < deadline, "the tutor's worker never listed the student of the other worker"
        students_page.close()
        while next_of(tutors_page, "state", timeout_s=3.0)["participants"] != ["tutor1"]:
            assert time.monotonic() < deadline + 3.0, "the student who left is still listed"
    finally:
        for server in servers:
            server.stop()
        for app in (first, second):
            _let_go(app)  # its ticker, and a practice keeper that would query the dropped database after
            session_factory(app).kw["bind"].dispose()


def test_a_password_changed_on_one_worker_closes_the_sockets_on_the_other_at_once(
        postgres_url: str, tmp_path: Path, skill_server_address: str) -> None:
    from middleware.auth.services import set_password
    from middleware.db import session_factory
    from middleware.realtime import CLOSE_NOT_LOGGED_IN
    from tests.integration.lab.test_robot_channels import closed_with

    robots = f"lab-1={skill_server_address}"
    first = make_test_app(postgres_url, robots, tmp_path / "one")
    second = make_test_app_without_user(postgres_url, robots, tmp_path / "two")
    server = LiveServer(first)
    try:
        student = LabClient(server.url)
        assert student.login() == 302
        link = student.websocket("/ws/link")
        time.sleep(0.5)
        with session_factory(second)() as session:  # the second worker: an admin resets the password
            set_password(session, "student1", "a-brand-new-password-1")
            session.commit()
        changed_at = time.monotonic()
        assert closed_with(link, 3.0) == CLOSE_NOT_LOGGED_IN
        print(f"\npassword changed on one worker -> socket closed on the other: "
              f"{(time.monotonic() - changed_at) * 1000:.0f} ms")
    finally:
        server.stop()
        for app in (first, second):
            _let_go(app)  # its ticker, and a practice keeper that would query the dropped database after
            session_factory(app).kw["bind"].dispose()


# Many at once, on one worker (SQLite) and on two workers of one PostgreSQL database: a class of CROWD students
# whose sockets are spread over the workers. One lab per database serves every case below (they leave the queue
# as they found it).
CROWD = 12


@dataclass
class Crowd:
    """The workers and a client of each student on each worker (a console may reconnect to either)."""

    servers: list[LiveServer]
    clients: dict[str, list[LabClient]]

    def on(self, index: int) -> tuple[str, LabClient]:
        """The index-th student and their client on the worker index picks (students alternate between them)."""
        name = sorted(self.clients)[index]
        return name, self.clients[name][index % len(self.servers)]


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def crowd(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory,
          skill_server_address: str) -> Iterator[Crowd]:
    from middleware.db import session_factory
    from tests.conftest import add_test_account, postgres_database

    robots = f"lab-1={skill_server_address}"
    folder = tmp_path_factory.mktemp(f"crowd-{request.param}")
    with contextlib.ExitStack() as stack:
        if request.param == "sqlite":
            apps = [make_test_app(f"sqlite:///{folder / 'lab.sqlite3'}", robots, folder)]
        else:
            database_url = stack.enter_context(postgres_database())
            apps = [make_test_app(database_url, robots, folder / "one"),
                    make_test_app_without_user(database_url, robots, folder / "two")]
        names = [f"crowd{i:02d}" for i in range(CROWD)]
        with session_factory(apps[0])() as session:
            for name in names:
                add_test_account(session, name, "student")
            session.commit()
        servers = [LiveServer(app) for app in apps]
        try:
            clients = {name: [LabClient(server.url) for server in servers] for name in names}
            for name, per_worker in clients.items():  # one at a time: logging in is not what is tested here
                assert all(client.login(name, STUDENT_PASSWORD) == 302 for client in per_worker), name
            yield Crowd(servers, clients)
        finally:
            for server in servers:
                server.stop()
            for app in apps:
                _let_go(app)
                session_factory(app).kw["bind"].dispose()


def _all_at_once(calls: list) -> list:
    """Runs the calls in threads released together; their results in order (the first failure is raised)."""
    barrier = threading.Barrier(len(calls))
    results: list = [None] * len(calls)
    errors: list[BaseException] = []

    def run(index: int) -> None:
        try:
            barrier.wait(10)
            results[index] = calls[index]()
        except BaseException as error:  # noqa: BLE001 - handed to the test's thread
            errors.append(error)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(len(calls))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    if errors:
        raise errors[0]
    return results


def _seat_until(ws, wanted, what: str, timeout_s: float = 5.0) -> dict:
    """The first queue message for which wanted(message) holds; fails naming what after timeout_s."""
    from tests.integration.lab.test_robot_channels import receive_json

    deadline, last = time.monotonic() + timeout_s, None
    while time.monotonic() < deadline:
        try:
            message = receive_json(ws, max(0.05, deadline - time.monotonic()))
        except AssertionError:
            break
        if message["type"] == "queue":
            last = message
            if wanted(message):
                return message
    raise AssertionError(f"{what}; the last seat shown: {last}")


def test_students_joining_and_leaving_at_once_are_shown_to_everyone_at_once(crowd: Crowd) -> None:
    """Joins within the same second each change the queue, and each is pushed to every page on every worker; so
    are waiting users leaving at once (the change itself is announced, not only what the rule did after it)."""
    sockets = _all_at_once([lambda i=i: crowd.on(i)[1].websocket("/ws/robots/lab-1/queue") for i in range(CROWD)])
    try:
        seats = [_seat_until(ws, lambda m: m["in_queue"] and m["queue_size"] == CROWD,
                             f"{crowd.on(i)[0]} never saw themselves among {CROWD} in the queue")
                 for i, ws in enumerate(sockets)]
        waiting = [i for i, seat in enumerate(seats) if not seat["is_controller"]]
        assert len(waiting) == CROWD - 1 and sorted(s["position"] for s in seats) == list(range(CROWD))
        leavers = waiting[-4:]
        _all_at_once([lambda i=i: sockets[i].send(json.dumps({"type": "leave"})) for i in leavers])
        for i, ws in enumerate(sockets):
            if i in leavers:
                _seat_until(ws, lambda m: not m["in_queue"], f"{crowd.on(i)[0]} left but is still shown in the queue")
            else:
                _seat_until(ws, lambda m: m["queue_size"] == CROWD - len(leavers),
                            f"{crowd.on(i)[0]} still sees the waiting users who left")
    finally:
        _leave_and_close(sockets)


def _leave_and_close(sockets: list) -> None:
    """Leaves the queue on every socket, as the case found it, and closes them."""
    for ws in sockets:
        with contextlib.suppress(Exception):
            ws.send(json.dumps({"type": "leave"}))
    for ws in sockets:
        with contextlib.suppress(Exception):
            _seat_until(ws, lambda m: not m["in_queue"], "a socket did not leave", timeout_s=3.0)
        with contextlib.suppress(Exception):
            ws.close()


def test_twelve_students_posting_at_once_each_read_every_message_live(crowd: Crowd) -> None:
    """Messages committed out of the order of their ids used to let a room's live cursor pass one still in flight:
    every receiver missed some of the 60 until a reload. Each socket here must read all of them as they come."""
    from middleware.chat.services import RATE_LIMIT_MESSAGES
    from tests.integration.chat.test_chat import say

    sockets = _all_at_once([lambda i=i: crowd.on(i)[1].websocket("/ws/robots/lab-1/chat") for i in range(CROWD)])
    try:
        for ws in sockets:
            next_of(ws, "history")
        bodies = {f"{crowd.on(i)[0]} says {n}" for i in range(CROWD) for n in range(RATE_LIMIT_MESSAGES)}

        def post_all(i: int) -> None:
            for n in range(RATE_LIMIT_MESSAGES):
                say(sockets[i], f"{crowd.on(i)[0]} says {n}")

        _all_at_once([lambda i=i: post_all(i) for i in range(CROWD)])
        for i, ws in enumerate(sockets):
            read: set[str] = set()
            deadline = time.monotonic() + 10.0
            while read != bodies and time.monotonic() < deadline:
                with contextlib.suppress(AssertionError):
                    read.add(next_of(ws, "message", timeout_s=max(0.1, deadline - time.monotonic()))["message"]["body"])
            assert read == bodies, f"{crowd.on(i)[0]} missed {len(bodies - read)} of {len(bodies)}: {bodies - read}"
    finally:
        for ws in sockets:
            with contextlib.suppress(Exception):
                ws.close()


@pytest.mark.parametrize("crowd", ["postgresql"], indirect=True)
def test_a_console_moved_to_the_other_worker_mid_turn_drives_with_its_next_command(crowd: Crowd) -> None:
    """Each worker numbered drive commands from a counter of its own, and the robot ignores a sequence that is not
    above the last of the same token: a console reconnected to the other worker was acknowledged but ignored for
    as many commands as it had sent. Here it drives on one worker, moves, and its first command there is applied,
    while the rest of the class waits in the queue."""
    from tests.integration.lab.test_robot_channels import drive_for, next_telemetry, pose, receive_json

    driver, _ = crowd.on(0)
    queue = crowd.clients[driver][0].websocket("/ws/robots/lab-1/queue")
    class_sockets: list = []
    try:
        _seat_until(queue, lambda m: m["is_controller"], "the driver did not get the robot")
        class_sockets = _all_at_once([lambda i=i: crowd.on(i)[1].websocket("/ws/robots/lab-1/queue")
                                      for i in range(1, CROWD)])
        telemetry = crowd.on(1)[1].websocket("/ws/robots/lab-1/telemetry")
        for move, worker in enumerate((1, 0, 1, 0)):
            speed = 0.2 if move % 2 == 0 else -0.2  # back and forth: the shared robot ends where it began
            drive = crowd.clients[driver][worker].websocket("/ws/robots/lab-1/drive")
            ready = receive_json(drive)
            assert ready["type"] == "ready" and ready["is_controller"], ready
            before = pose(next_telemetry(telemetry))
            drive.send(json.dumps({"type": "drive", "sequence": 1, "linear_mps": speed, "angular_radps": 0.0}))
            ack = receive_json(drive)
            assert ack["type"] == "ack" and ack["applied_sequence"] == 1, \
                f"the first command on worker {worker} was acknowledged but not applied: {ack}"
            drive_for(drive, 0.6, speed, 0.0, 2)
            moved = pose(next_telemetry(telemetry))
            assert abs(moved[0] - before[0]) + abs(moved[1] - before[1]) > 0.02, f"no motion on worker {worker}"
            drive.close()
        _seat_until(queue, lambda m: m["is_controller"] and m["queue_size"] == CROWD,
                    "the driver lost the seat, or the class is not waiting behind them")
    finally:
        _leave_and_close([queue, *class_sockets])
