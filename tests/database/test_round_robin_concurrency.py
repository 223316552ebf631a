"""Several worker processes join, leave, pass and tick one robot at once: never two controllers.

Each process runs a random schedule against the same database. The schema gives each robot one
control row, so "two controllers at one moment" would show as one token handed to two users, a
controller without a seat, or a process failing on a lock; the test looks for all three.
"""

from __future__ import annotations

import multiprocessing
import random
import time
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from middleware.access import round_robin
from middleware.access.round_robin import AccessPolicy
from middleware.db import make_engine
from middleware.models import QueueEntry, RobotControl, User
from tests.conftest import migrate_to_head

ROBOT = "lab-1"
WORKERS = 3
OPERATIONS_PER_WORKER = 60
# The schedule's clock runs 50x faster than the wall clock, so turns (2 s) and grace (1 s) expire often.
CLOCK_SPEEDUP = 50.0
T0 = datetime(2026, 11, 21, 9, 0, tzinfo=UTC)


def _worker(database_url: str, user_ids: list[int], seed: int, started: float, results) -> None:
    engine = make_engine(database_url)
    policy = AccessPolicy(grace_s=1.0, turn_length_s=lambda _s, _u: 2.0)
    rng = random.Random(seed)
    observations: list[tuple[str | None, int | None]] = []
    try:
        for _ in range(OPERATIONS_PER_WORKER):
            now = T0 + timedelta(seconds=(time.monotonic() - started) * CLOCK_SPEEDUP)
            user_id = rng.choice(user_ids)
            kind = rng.choice(["join", "join", "heartbeat", "tick", "tick", "pass", "leave"])
            with Session(engine) as session, session.begin():
                if kind == "heartbeat":
                    round_robin.heartbeat(session, ROBOT, user_id, now)
                    continue
                operation = {"join": round_robin.join, "pass": round_robin.pass_turn,
                             "leave": round_robin.leave}.get(kind)
                if operation is None:
                    state = round_robin.tick(session, ROBOT, policy, now)
                else:
                    state = operation(session, ROBOT, user_id, policy, now)
                observations.append((state.token, state.controller_id))
            time.sleep(rng.random() * 0.01)
        results.put(("ok", observations))
    except Exception as error:  # noqa: BLE001 - reported to the test, which fails on it
        results.put(("error", repr(error)))
    finally:
        engine.dispose()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_concurrent_workers_never_produce_two_controllers(database_url: str, seed: int) -> None:
    migrate_to_head(database_url)
    engine = make_engine(database_url)
    with Session(engine) as session:
        users = [User(username=f"user{i}", role="student", password_hash="x") for i in range(6)]
        session.add_all(users)
        session.commit()
        user_ids = [u.id for u in users]

    # New processes, not forks of this one (its threads and connections), each importing only what a fork of the
    # fork server already holds: a spawned process spent about 2 s of CPU importing the middleware, 18 times a run.
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload([__name__])
    results = context.Queue()
    started = time.monotonic()
    workers = [
        context.Process(target=_worker, args=(database_url, user_ids, seed * 100 + n, started, results))
        for n in range(WORKERS)
    ]
    for worker in workers:
        worker.start()
    outcomes = [results.get(timeout=120) for _ in workers]
    for worker in workers:
        worker.join(10)

    errors = [detail for status, detail in outcomes if status == "error"]
    assert not errors, f"a worker failed: {errors}"
    holder_of_token: dict[str, int | None] = {}
    for _, observations in outcomes:
        for token, controller_id in observations:
            if token is None:
                assert controller_id is None
                continue
            assert holder_of_token.setdefault(token, controller_id) == controller_id, "one token, two controllers"
    assert len(holder_of_token) > 3, "the schedule should have rotated control several times"

    with Session(engine) as session:
        control = session.get(RobotControl, ROBOT)
        assert control is not None
        seats = session.scalars(select(QueueEntry.user_id).where(QueueEntry.robot_name == ROBOT)).all()
        assert len(seats) == len(set(seats))
        if control.controller_id is not None:
            assert control.controller_id in seats, "the controller always holds a seat"
        assert session.scalar(select(func.count()).select_from(RobotControl)) == 1
    engine.dispose()
