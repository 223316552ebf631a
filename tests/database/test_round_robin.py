"""The round-robin rule with a controllable clock, on SQLite and PostgreSQL."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import Engine
from sqlalchemy.orm import Session

from middleware.access import round_robin
from middleware.access.round_robin import AccessPolicy, QueueState
from middleware.models import User

T0 = datetime(2026, 11, 21, 9, 0, tzinfo=UTC)
TURN_S = 120.0
ROBOT = "lab-1"


@pytest.fixture
def users(engine: Engine) -> dict[str, int]:
    with Session(engine) as session:
        accounts = {name: User(username=name, role="student", password_hash="x") for name in ("ann", "bob", "cy")}
        session.add_all(accounts.values())
        session.commit()
        return {name: user.id for name, user in accounts.items()}


class Lab:
    """Runs round-robin operations one transaction each, as the coordinator does, at chosen times."""

    def __init__(self, engine: Engine, priority: int | None = None) -> None:
        self.engine = engine
        self.priority = priority
        self.policy = AccessPolicy(grace_s=15.0, turn_length_s=lambda _s, _u: TURN_S,
                                   priority_user_id=lambda _s, _r, _n: self.priority)

    def run(self, operation, *args: object, at_s: float, online: bool = True) -> QueueState:
        with Session(self.engine) as session, session.begin():
            return operation(session, ROBOT, *args, self.policy, T0 + timedelta(seconds=at_s), online)

    def join(self, user_id: int, at_s: float) -> QueueState:
        return self.run(round_robin.join, user_id, at_s=at_s)

    def tick(self, at_s: float, online: bool = True) -> QueueState:
        return self.run(round_robin.tick, at_s=at_s, online=online)

    def seen(self, user_ids: list[int], at_s: float) -> None:
        with Session(self.engine) as session, session.begin():
            for user_id in user_ids:
                assert round_robin.heartbeat(session, ROBOT, user_id, T0 + timedelta(seconds=at_s))


def test_a_single_user_keeps_control_with_no_time_limit(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    state = lab.join(users["ann"], at_s=0)
    assert state.controller_id == users["ann"] and state.turn_ends_at is None and state.token
    for minute in range(1, 60, 7):
        lab.seen([users["ann"]], at_s=minute * 60)
        state = lab.tick(at_s=minute * 60 + 1)
        assert state.controller_id == users["ann"] and state.turn_ends_at is None


def test_with_three_users_turns_rotate_in_order_and_the_previous_controller_goes_to_the_back(
    engine: Engine, users: dict[str, int]
) -> None:
    lab = Lab(engine)
    ann, bob, cy = users["ann"], users["bob"], users["cy"]
    lab.join(ann, at_s=0)
    lab.join(bob, at_s=1)
    state = lab.join(cy, at_s=2)
    assert state.controller_id == ann and state.waiting_ids == (bob, cy)
    assert state.turn_ends_at == T0 + timedelta(seconds=1 + TURN_S), "the turn is limited once someone waits"
    tokens = [state.token]
    expected_order = [bob, cy, ann, bob]
    now = 1.0
    for expected in expected_order:
        lab.seen([ann, bob, cy], at_s=now + TURN_S - 1)
        assert lab.tick(at_s=now + TURN_S - 1).controller_id != expected, "the turn ended early"
        state = lab.tick(at_s=now + TURN_S)
        assert state.controller_id == expected
        assert state.waiting_ids[-1] != expected and len(state.waiting_ids) == 2
        tokens.append(state.token)
        now += TURN_S
    assert len(set(tokens)) == len(tokens), "every grant hands out a new token"


def test_a_reload_within_grace_keeps_the_seat_and_a_user_gone_past_grace_leaves(
    engine: Engine, users: dict[str, int]
) -> None:
    lab = Lab(engine)
    ann, bob, cy = users["ann"], users["bob"], users["cy"]
    lab.join(ann, at_s=0)
    lab.join(bob, at_s=1)
    lab.join(cy, at_s=2)
    lab.seen([ann, cy], at_s=10)
    state = lab.join(bob, at_s=15)  # bob reloads the page 14 s after his last sign of life
    assert state.waiting_ids == (bob, cy), "bob kept his place in front of cy"
    lab.seen([ann, bob], at_s=20)
    state = lab.tick(at_s=2 + 15.5)  # cy was last seen at 10 s: gone past the 15 s grace at 25 s, not yet
    assert cy in state.waiting_ids
    state = lab.tick(at_s=26)
    assert state.waiting_ids == (bob,)


def test_the_controller_gone_past_grace_hands_control_to_the_next(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    lab.join(users["ann"], at_s=0)
    lab.join(users["bob"], at_s=1)
    lab.seen([users["bob"]], at_s=14)
    state = lab.tick(at_s=16)
    assert state.controller_id == users["bob"] and state.waiting_ids == () and state.turn_ends_at is None


def test_a_fault_during_a_turn_keeps_the_controller_at_the_head(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    ann, bob = users["ann"], users["bob"]
    lab.join(ann, at_s=0)
    lab.join(bob, at_s=1)
    lab.seen([ann, bob], at_s=95)
    state = lab.tick(at_s=100, online=False)
    assert state.faulted and state.controller_id == ann and state.turn_ends_at is None
    lab.seen([ann, bob], at_s=290)
    state = lab.tick(at_s=300, online=False)  # the robot is still down long after ann's turn would have ended
    assert state.controller_id == ann
    state = lab.tick(at_s=301, online=True)
    assert state.controller_id == ann and not state.faulted
    assert state.turn_ends_at == T0 + timedelta(seconds=301 + TURN_S), "ann gets a full turn when the robot returns"


def test_those_waiting_for_an_offline_robot_are_told_no_turn_can_start(
        engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    ann = users["ann"]
    state = lab.run(round_robin.join, ann, at_s=0, online=False)
    assert state.controller_id is None and state.faulted
    seat = round_robin.seat_of(state, ann, T0, TURN_S)
    assert seat.in_queue and seat.faulted and seat.estimated_wait_s is None, "not 'your turn in 0:00'"
    state = lab.tick(at_s=1, online=True)
    assert state.controller_id == ann and not state.faulted


def test_passing_early_and_leaving(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    ann, bob, cy = users["ann"], users["bob"], users["cy"]
    for offset, user in enumerate((ann, bob, cy)):
        lab.join(user, at_s=offset)
    state = lab.run(round_robin.pass_turn, bob, at_s=5)
    assert state.controller_id == ann, "only the controller can pass"
    state = lab.run(round_robin.pass_turn, ann, at_s=6)
    assert state.controller_id == bob and state.waiting_ids == (cy, ann)
    state = lab.run(round_robin.leave, bob, at_s=7)
    assert state.controller_id == cy and state.waiting_ids == (ann,)
    state = lab.run(round_robin.leave, ann, at_s=8)
    assert state.controller_id == cy and state.turn_ends_at is None, "alone again: no time limit"
    state = lab.run(round_robin.leave, cy, at_s=9)
    assert state.controller_id is None and state.token is None


def test_a_booked_user_gets_control_first(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    ann, bob = users["ann"], users["bob"]
    lab.join(ann, at_s=0)
    lab.priority = bob
    state = lab.join(bob, at_s=1)
    assert state.controller_id == bob and state.waiting_ids == (ann,)
    lab.seen([ann, bob], at_s=500)
    assert lab.tick(at_s=500).controller_id == bob, "a booking is not cut into turns"
    lab.priority = None
    state = lab.tick(at_s=501)
    assert state.controller_id == bob and state.turn_ends_at == T0 + timedelta(seconds=501 + TURN_S)


def test_what_each_user_sees(engine: Engine, users: dict[str, int]) -> None:
    lab = Lab(engine)
    ann, bob, cy = users["ann"], users["bob"], users["cy"]
    for offset, user in enumerate((ann, bob, cy)):
        state = lab.join(user, at_s=offset)
    now = T0 + timedelta(seconds=1 + TURN_S - 15)
    controller = round_robin.seat_of(state, ann, now, TURN_S)
    assert controller.is_controller and controller.turn_remaining_s == 15 and controller.warning
    second = round_robin.seat_of(state, bob, now, TURN_S)
    assert (second.position, second.queue_size, second.estimated_wait_s) == (1, 3, 15)
    third = round_robin.seat_of(state, cy, now, TURN_S)
    assert (third.position, third.estimated_wait_s, third.warning) == (2, 15 + TURN_S, False)
    stranger = round_robin.seat_of(state, 9999, now, TURN_S)
    assert not stranger.in_queue and stranger.position == -1
