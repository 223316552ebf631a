"""The pool rule inside round-robin: a waiter for "any robot of kind K" is bound to the robot that can start their
turn first, counts as someone waiting for every robot of K, and is never bound twice; on SQLite and PostgreSQL."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from middleware.access import pools, round_robin
from middleware.access.round_robin import AccessPolicy, QueueState
from middleware.models import PoolQueueEntry, QueueEntry, Robot, User

T0 = datetime(2026, 11, 25, 9, 0, tzinfo=UTC)
TURN_S = 120.0
GRACE_S = 15.0


@pytest.fixture
def users(engine: Engine) -> dict[str, int]:
    with Session(engine) as session:
        accounts = {name: User(username=name, role="student", password_hash="x")
                    for name in ("ann", "bob", "cy", "dee")}
        session.add_all(accounts.values())
        session.add_all([Robot(name="sim-1", title="Sim 1", address="127.0.0.1:9", kind="sim"),
                         Robot(name="sim-2", title="Sim 2", address="127.0.0.1:9", kind="sim"),
                         Robot(name="other-1", title="Other", address="127.0.0.1:9", kind="other")])
        session.commit()
        return {name: user.id for name, user in accounts.items()}


class Pool:
    def __init__(self, engine: Engine, priority: dict[str, int] | None = None) -> None:
        self.engine = engine
        self.priority = priority or {}
        self.policy = AccessPolicy(GRACE_S, lambda _s, _u: TURN_S, lambda _s, robot, _n: self.priority.get(robot))

    def at(self, seconds: float) -> datetime:
        return T0 + timedelta(seconds=seconds)

    def wait(self, user_id: int, at_s: float, kind: str = "sim") -> None:
        with Session(self.engine) as session, session.begin():
            pools.join(session, kind, user_id, self.at(at_s))

    def join(self, robot: str, user_id: int, at_s: float) -> QueueState:
        with Session(self.engine) as session, session.begin():
            return round_robin.join(session, robot, user_id, self.policy, self.at(at_s))

    def tick(self, robot: str, at_s: float) -> QueueState:
        with Session(self.engine) as session, session.begin():
            return round_robin.tick(session, robot, self.policy, self.at(at_s))

    def waiting(self, at_s: float, kind: str = "sim") -> list[int]:
        with Session(self.engine) as session, session.begin():
            return pools.waiting(session, kind, self.at(at_s), GRACE_S)

    def seen(self, robot: str, user_ids: list[int], at_s: float) -> None:
        with Session(self.engine) as session, session.begin():
            for user_id in user_ids:
                round_robin.heartbeat(session, robot, user_id, self.at(at_s))


def test_a_free_robot_binds_the_first_pool_waiter_and_the_pool_entry_becomes_its_seat(engine, users) -> None:
    pool = Pool(engine)
    pool.wait(users["ann"], at_s=0)
    state = pool.tick("sim-1", at_s=0.1)
    assert state.controller_id == users["ann"] and state.token
    assert pool.waiting(at_s=0.2) == []
    with Session(engine) as session:
        assert pools.bound_robot(session, "sim", users["ann"]) == "sim-1"
    assert pool.tick("sim-2", at_s=0.3).controller_id is None, "one waiter, one robot"


def test_a_pool_waiter_limits_a_lone_controllers_turn_and_takes_over_at_its_end(engine, users) -> None:
    pool = Pool(engine)
    ann, bob, cy = users["ann"], users["bob"], users["cy"]
    pool.join("sim-1", ann, at_s=0)
    pool.join("sim-2", bob, at_s=0)
    assert pool.tick("sim-1", at_s=1).turn_ends_at is None, "alone, no limit"
    pool.wait(cy, at_s=5)
    limited = pool.tick("sim-1", at_s=6)
    assert limited.turn_ends_at == pool.at(6 + TURN_S)
    assert pool.tick("sim-2", at_s=7).turn_ends_at == pool.at(7 + TURN_S)
    for second in range(10, int(TURN_S) + 6, 10):
        pool.wait(cy, at_s=second)
        pool.seen("sim-1", [ann], at_s=second)
        pool.seen("sim-2", [bob], at_s=second)
    turned = pool.tick("sim-1", at_s=TURN_S + 6)
    assert turned.controller_id == cy and turned.waiting_ids == (ann,), "ann goes to the end of sim-1's queue"
    kept = pool.tick("sim-2", at_s=TURN_S + 7)
    assert kept.controller_id == bob, "cy is bound to one robot only"
    assert pool.tick("sim-2", at_s=TURN_S + 8).turn_ends_at is None, "nobody waits for sim-2 any more"


def test_two_robots_settling_at_once_never_bind_the_same_waiter(engine, users) -> None:
    pool = Pool(engine)
    pool.wait(users["ann"], at_s=0)
    with Session(engine) as first, Session(engine) as second:
        first.begin()
        a = round_robin.tick(first, "sim-1", pool.policy, pool.at(1))
        first.commit()
        second.begin()
        b = round_robin.tick(second, "sim-2", pool.policy, pool.at(1))
        second.commit()
    assert [a.controller_id, b.controller_id].count(users["ann"]) == 1
    with Session(engine) as session:
        seats = session.scalars(select(QueueEntry.robot_name).where(QueueEntry.user_id == users["ann"])).all()
    assert seats == ["sim-1"]


def test_a_waiters_heartbeat_while_a_robot_binds_them_keeps_them_bound_once_and_raises_nothing(engine, users) -> None:
    """The page's heartbeat read "not bound" just before a robot's rule bound the waiter in another transaction
    (seen as a 500: the heartbeat's UPDATE of the vanished pool entry matched no row)."""
    pool = Pool(engine)
    ann = users["ann"]
    pool.wait(ann, at_s=0)
    with Session(engine) as heartbeat:
        heartbeat.begin()
        assert pools.bound_robot(heartbeat, "sim", ann) is None
        assert pool.tick("sim-1", at_s=1).controller_id == ann
        pools.join(heartbeat, "sim", ann, pool.at(1.1))
        heartbeat.commit()
    assert pool.waiting(at_s=2) == [], "a bound waiter is not queued again"
    pool.wait(users["bob"], at_s=3)
    pool.wait(users["bob"], at_s=4)
    assert pool.waiting(at_s=5) == [users["bob"]]


def test_waiters_are_bound_in_order_unheard_ones_drop_out_and_other_kinds_are_untouched(engine, users) -> None:
    pool = Pool(engine)
    pool.wait(users["ann"], at_s=0)
    pool.wait(users["bob"], at_s=1)
    pool.wait(users["dee"], at_s=1, kind="other")
    assert pool.waiting(at_s=20) == [], "both went quiet past the grace period"
    pool.wait(users["bob"], at_s=21)
    pool.wait(users["cy"], at_s=22)
    assert pool.tick("sim-2", at_s=23).controller_id == users["bob"]
    assert pool.tick("sim-1", at_s=23).controller_id == users["cy"]
    with Session(engine) as session:
        kinds = session.scalars(select(PoolQueueEntry.kind)).all()
    assert kinds == ["other"], "binding sim waiters neither binds nor drops a waiter of another kind"


def test_a_pool_bookings_holder_waiting_in_the_pool_is_bound_first_on_the_booked_robot(engine, users) -> None:
    pool = Pool(engine)
    ann, bob = users["ann"], users["bob"]
    pool.join("sim-1", ann, at_s=0)
    pool.priority["sim-1"] = bob  # the slot bound to sim-1 starts: bob holds it
    pool.wait(bob, at_s=1)
    state = pool.tick("sim-1", at_s=2)
    assert state.controller_id == bob and state.waiting_ids == (ann,)
    assert state.turn_ends_at is None, "a booking's holder has no turn limit"


def test_a_disabled_robot_binds_nobody(engine, users) -> None:
    with Session(engine) as session:
        session.scalar(select(Robot).where(Robot.name == "sim-1")).enabled = False
        session.commit()
    pool = Pool(engine)
    pool.wait(users["ann"], at_s=0)
    assert pool.tick("sim-1", at_s=1).controller_id is None
    assert pool.waiting(at_s=2) == [users["ann"]]


def test_a_pool_booking_is_bound_at_its_start_to_a_robot_free_for_the_whole_slot(engine, users) -> None:
    from middleware.bookings.services import priority_user_id
    from middleware.models import Booking

    ten = T0.replace(hour=10)
    with Session(engine) as session:
        session.add_all([
            Booking(robot_name=None, pool_kind="sim", user_id=users["bob"], kind="personal", starts_at=ten,
                    ends_at=ten + timedelta(hours=1)),
            Booking(robot_name="sim-1", user_id=users["ann"], kind="personal", starts_at=ten + timedelta(minutes=30),
                    ends_at=ten + timedelta(hours=1))])
        session.commit()
    with Session(engine) as session, session.begin():
        assert priority_user_id(session, "sim-1", ten - timedelta(minutes=1), grace_s=600) is None, "not yet"
        assert priority_user_id(session, "sim-1", ten, grace_s=600) is None, "sim-1 is booked later in the slot"
        assert priority_user_id(session, "sim-2", ten, grace_s=600) == users["bob"]
    with Session(engine) as session:
        bound = session.scalar(select(Booking).where(Booking.pool_kind == "sim"))
        assert bound.robot_name == "sim-2"
    with Session(engine) as session, session.begin():
        assert priority_user_id(session, "sim-1", ten + timedelta(minutes=5), grace_s=600) is None
        assert priority_user_id(session, "sim-2", ten + timedelta(minutes=5), grace_s=600) == users["bob"]
