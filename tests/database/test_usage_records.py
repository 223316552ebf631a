"""What usage analytics needs that the access rule records where it decides (on SQLite and PostgreSQL): each turn
granted with how long it was waited for, and each time a robot did not answer (its outage, opened when a tick
finds it offline and closed when it answers again)."""

from __future__ import annotations

from datetime import timedelta

from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from middleware.models.accounts import as_utc
from middleware.models.analytics import QueueWait, RobotOutage
from tests.database.test_round_robin import T0, TURN_S, Lab, users  # noqa: F401 - users is a fixture


def test_each_turn_granted_records_how_long_it_was_waited_for(engine: Engine, users: dict[str, int]) -> None:  # noqa: F811
    lab = Lab(engine)
    lab.join(users["ann"], at_s=0)  # a free robot: ann's turn at once
    lab.join(users["bob"], at_s=10)  # bob waits for ann's turn to end (at 10 + 120 s)
    for second in range(20, 140, 10):
        lab.seen([users["ann"], users["bob"]], at_s=second)
    state = lab.tick(at_s=10 + TURN_S + 1)
    assert state.controller_id == users["bob"]
    with Session(engine) as session:
        waits = [(w.user_id, w.wait_s, as_utc(w.granted_at)) for w in session.scalars(
            select(QueueWait).order_by(QueueWait.id))]
    assert waits == [(users["ann"], 0.0, T0), (users["bob"], TURN_S + 1, T0 + timedelta(seconds=10 + TURN_S + 1))]


def test_a_robot_that_stops_answering_opens_an_outage_closed_when_it_answers(engine: Engine,
                                                                              users: dict[str, int]) -> None:  # noqa: F811
    lab = Lab(engine)
    lab.join(users["ann"], at_s=0)
    lab.tick(at_s=10, online=False)
    lab.tick(at_s=20, online=False)  # still down: the same outage
    lab.tick(at_s=70)
    lab.tick(at_s=80, online=False)
    with Session(engine) as session:
        outages = [(as_utc(o.started_at), as_utc(o.ended_at) if o.ended_at else None)
                   for o in session.scalars(select(RobotOutage).order_by(RobotOutage.id))]
    assert outages == [(T0 + timedelta(seconds=10), T0 + timedelta(seconds=70)), (T0 + timedelta(seconds=80), None)]
