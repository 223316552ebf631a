"""Whether each robot answered its last probe, probed on threads of their own so the ticker never waits for one.

The ticker expires seats past their grace: a pass that asked every robot in turn whether it answers spent a whole
call deadline on each robot that did not, so three slow robots held a vanished user's seat 3 s past the grace. The
ticker reads the last answers here instead, and starts the next probes without waiting for them.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor

log = logging.getLogger(__name__)
PROBES_AT_ONCE = 8


class RobotLiveness:
    """The last answer of each robot's probe (online or not); one probe per robot in flight at a time."""

    def __init__(self, probe: Callable[[str], bool], probes_at_once: int = PROBES_AT_ONCE) -> None:
        self._probe = probe
        self._answers: dict[str, bool] = {}
        self._in_flight: set[str] = set()
        self._lock = threading.Lock()
        self._pool = ThreadPoolExecutor(probes_at_once, thread_name_prefix="robot-liveness")
        self._closed = False

    def probe(self, robot_names: Iterable[str]) -> None:
        """Starts a probe of each robot whose last one has answered (never waits for one)."""
        with self._lock:
            if self._closed:
                return
            for name in robot_names:
                if name not in self._in_flight:
                    self._in_flight.add(name)
                    self._pool.submit(self._run, name)

    def last(self, robot_name: str) -> bool | None:
        """Whether the robot answered its last probe; None before its first probe answered."""
        return self._answers.get(robot_name)

    def close(self) -> None:
        """No more probes; those under way end within their call's deadline."""
        with self._lock:
            self._closed = True
        self._pool.shutdown(wait=False, cancel_futures=True)

    def _run(self, name: str) -> None:
        try:
            online = self._probe(name)
        except Exception:  # noqa: BLE001 - a probe that fails says the robot does not answer
            log.exception("probing %s failed", name)
            online = False
        with self._lock:
            self._answers[name] = online
            self._in_flight.discard(name)
