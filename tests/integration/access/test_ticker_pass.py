"""The access ticker's pass reads every robot's queue at once and runs the locked rule only for a robot with something
due: a class of robots each driven by its one student costs the same few queries however many robots there are (a
transaction per robot every tick, with its priority reads, was a fifth of a worker's time in a class of 50), and what
time and faults change is still changed on the next pass (a seat past grace, an offline robot, a booking under way)."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from sqlalchemy import event, select

from benchmarks.standin_robots import StandInFleet
from tests.conftest import add_test_account, make_test_app

ROBOTS = 12


@pytest.fixture(scope="module")
def fleet() -> Iterator[StandInFleet]:
    robots = StandInFleet(ROBOTS, "tick-")
    try:
        yield robots
    finally:
        robots.stop()


@pytest.fixture
def class_of_drivers(database_url: str, fleet: StandInFleet, tmp_path: Path) -> Iterator[tuple[object, list[int]]]:
    """The app with every robot held by a student of its own (each alone on it, as in a class)."""
    from middleware.access.coordinator import access_coordinator
    from middleware.db import session_factory
    from middleware.robots.registry import robot_registry

    app = make_test_app(database_url, fleet.robots_setting, tmp_path)
    with session_factory(app)() as session:
        students = [add_test_account(session, f"driver{i}", "student").id for i in range(ROBOTS)]
        session.commit()
    coordinator = access_coordinator(app)
    for robot_name, student in zip(fleet.addresses, students, strict=True):
        assert coordinator.join(robot_name, student).controller_id == student
    try:
        yield app, students
    finally:
        robot_registry(app).close()
        session_factory(app).kw["bind"].dispose()


def statements_of(app, during) -> list[str]:  # noqa: ANN001 - the app, a call
    from middleware.db import session_factory

    engine = session_factory(app).kw["bind"]
    seen: list[str] = []

    def note(_connection, _cursor, statement, *_args) -> None:  # noqa: ANN001
        seen.append(statement)

    event.listen(engine, "before_cursor_execute", note)
    try:
        during()
    finally:
        event.remove(engine, "before_cursor_execute", note)
    return seen


def test_a_class_of_drivers_costs_one_read_of_every_queue_and_no_transaction_per_robot(class_of_drivers) -> None:
    from middleware.access.coordinator import access_coordinator

    app, _students = class_of_drivers
    coordinator = access_coordinator(app)
    online = dict.fromkeys(coordinator_names(app), True)
    ticked: list[list[str]] = []
    statements = statements_of(app, lambda: ticked.append(coordinator.tick_all(online)))
    assert ticked == [[]], "nothing is due on robots each held by its one student"
    assert len(statements) <= 12, statements  # before: a locked transaction of about ten queries per robot
    assert not [s for s in statements if "FOR UPDATE" in s or s.lstrip().upper().startswith(("UPDATE", "INSERT"))]


def test_what_time_and_faults_change_is_still_changed(class_of_drivers) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.db import session_factory
    from middleware.models import Booking, RobotControl

    app, students = class_of_drivers
    coordinator = access_coordinator(app)
    names = coordinator_names(app)
    online = dict.fromkeys(names, True)
    online[names[0]] = False  # stopped answering: its seat is kept, the robot marked faulted
    now = datetime.now(UTC)
    with session_factory(app)() as session:  # a booking under way on the second robot: the priority rule speaks
        session.add(Booking(robot_name=names[1], user_id=students[1], kind="personal", starts_at=now - timedelta(
            minutes=1), ends_at=now + timedelta(minutes=29), checked_in_at=now))
        session.commit()
    assert coordinator.tick_all(online) == [names[0], names[1]]
    with session_factory(app)() as session:
        assert session.get(RobotControl, names[0]).faulted
    assert coordinator.tick_all(online) == [names[1]]  # the fault is set: quiet again

    grace_s = coordinator.policy.grace_s
    coordinator.clock = lambda: datetime.now(UTC) + timedelta(seconds=grace_s + 5)  # nobody heard since: seats go
    assert sorted(coordinator.tick_all(online)) == sorted(names)
    with session_factory(app)() as session:
        assert session.scalars(select(RobotControl.controller_id).where(RobotControl.robot_name.in_(names[2:]))
                               ).all() == [None] * (len(names) - 2)


def coordinator_names(app) -> list[str]:  # noqa: ANN001
    from middleware.robots.registry import robot_registry

    return robot_registry(app).names()
