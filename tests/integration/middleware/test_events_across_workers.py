"""Two web workers on one PostgreSQL database hear each other's changes through LISTEN/NOTIFY at once (nothing
polls the tables): a chat message posted or deleted through one reaches a socket on the other, a robot an admin
adds through one is in the other's lab, a delay a tutor sets through one is applied by the other's viewers; a
transaction that rolls back announces nothing."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, make_course, make_test_app
from tests.integration.bookings.conftest import api
from tests.integration.chat.test_chat import next_of


def test_a_message_posted_on_one_worker_reaches_a_socket_on_the_other_at_once(postgres_url: str, tmp_path: Path,
                                                                                skill_server_address: str) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.events import bus_of
    from middleware.lab.delay import delay_book

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
            access_coordinator(app).stop_ticker()
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

    from middleware.access.coordinator import access_coordinator
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
            access_coordinator(app).stop_ticker()
            session_factory(app).kw["bind"].dispose()


def test_a_password_changed_on_one_worker_closes_the_sockets_on_the_other_at_once(
        postgres_url: str, tmp_path: Path, skill_server_address: str) -> None:
    from middleware.access.coordinator import access_coordinator
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
            access_coordinator(app).stop_ticker()
            session_factory(app).kw["bind"].dispose()
