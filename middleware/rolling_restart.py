"""Gunicorn's master for rolling restarts: after a reload (SIGHUP) each old worker leaves only once a new one serves.

Imported only by the gunicorn hook that installs it (serve.roll_restarts), so `telelab web` and the tests' servers do
not import gunicorn.
"""

from __future__ import annotations

import os
import signal
import time
from typing import Any

from gunicorn.arbiter import Arbiter  # type: ignore[import-untyped]


def serves(worker: Any) -> bool:
    """Whether a worker has made its app and serves (settle_worker wrote its byte)."""
    try:
        return os.fstat(worker.tmp.fileno()).st_size > 0
    except (OSError, ValueError):
        return False


class RollingArbiter(Arbiter):
    """gunicorn's master, except that after a reload (SIGHUP) each old worker is retired only once a new one serves.

    gunicorn's own reload forks the new generation and sends SIGTERM to the old one at once; a new worker then takes
    seconds to make its app, so consoles found no worker for 1-6 s. Here the old workers keep serving until as many
    new ones serve (or until `timeout`, should a new one never come up).
    """

    def manage_workers(self) -> None:
        retiring: set[int] = self.__dict__.setdefault("_retiring", set())
        retiring &= set(self.WORKERS)
        serving = [pid for pid in self.WORKERS if pid not in retiring]
        for _ in range(self.num_workers - len(serving)):
            self.spawn_worker()
        if len(serving) > self.num_workers:
            self._retire_as_replaced(retiring)

    def _retire_as_replaced(self, retiring: set[int]) -> None:
        deadline = time.monotonic() + self.cfg.timeout
        while True:
            self.reap_workers()
            retiring &= set(self.WORKERS)
            serving = {pid: worker for pid, worker in self.WORKERS.items() if pid not in retiring}
            if len(serving) <= self.num_workers:
                return
            ready = sum(1 for worker in serving.values() if serves(worker))
            if ready > self.num_workers or time.monotonic() > deadline:
                oldest = min(serving, key=lambda pid: serving[pid].age)
                self.kill_worker(oldest, signal.SIGTERM)
                retiring.add(oldest)
                continue
            time.sleep(0.05)
