"""The access ticker runs in one process of a cluster: on PostgreSQL an advisory lock elects it, and when that
process goes (its connection closes) another takes over within a tick; on SQLite the one process always ticks."""

from __future__ import annotations

import time

from sqlalchemy import create_engine

from middleware.access.coordinator import ACCESS_TICKER_LOCK
from middleware.locking import ClusterElection


def test_one_process_leads_and_another_takes_over_within_a_tick_when_it_goes(database_url: str) -> None:
    engines = [create_engine(database_url), create_engine(database_url)]
    first, second = (ClusterElection(engine, ACCESS_TICKER_LOCK) for engine in engines)
    try:
        if not database_url.startswith("postgresql"):
            assert first.leads() and second.leads(), "SQLite: one process, which always ticks"
            return
        assert first.leads() and not second.leads()
        assert first.leads() and not second.leads(), "the leader keeps the lock from tick to tick"
        gone_at = time.monotonic()
        first._connection.invalidate()  # noqa: SLF001 - the process died: its connection is gone
        first._connection = None  # noqa: SLF001
        first._held = False  # noqa: SLF001
        while not second.leads():
            assert time.monotonic() - gone_at < 1.0, "nobody took the ticker over within a second"
            time.sleep(0.05)
        assert not first.leads(), "the old leader, back, does not tick beside the new one"
        second.resign()
        assert first.leads(), "a process that stops gives the ticker up at once"
    finally:
        first.resign()
        second.resign()
        for engine in engines:
            engine.dispose()
