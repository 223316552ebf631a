"""The skill server's process as a tutor diagnoses it (CPU, memory, uptime, version, the last lines of its log) and
its restart (the 2003 paper's remote reboot): the process starts itself again on the same address, keeping its
controller, so its supervisor (a farm or `telelab up`) sees the same process go on."""

from __future__ import annotations

import logging
import os
import resource
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import metadata

LOG_LINES_KEPT = 50
RESTARTS_VARIABLE = "TELELAB_ROBOT_RESTARTS"  # carried through the restart, so the count survives it
# Read from the environment, not the command line, so other users of the host cannot read it off `ps`.
CONTROLLER_TOKEN_VARIABLE = "TELELAB_CONTROLLER_TOKEN"
_PAGE_BYTES = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


class LogTail(logging.Handler):
    """The last lines the process logged, for a tutor reading why a robot misbehaves."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
        self._lines: deque[str] = deque(maxlen=LOG_LINES_KEPT)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self._lines.append(self.format(record))
        except Exception:  # noqa: BLE001 - a log line that cannot be formatted must not break the robot
            self.handleError(record)

    def lines(self) -> list[str]:
        return list(self._lines)


_tail_lock = threading.Lock()
_tail: LogTail | None = None


def log_tail() -> LogTail:
    """The process's one log tail, on the root logger from the first call on."""
    global _tail
    with _tail_lock:
        if _tail is None:
            _tail = LogTail()
            logging.getLogger().addHandler(_tail)
            if logging.getLogger().level > logging.INFO:
                logging.getLogger().setLevel(logging.INFO)
        return _tail


def version() -> str:
    try:
        return metadata.version("telelab")
    except metadata.PackageNotFoundError:
        return "unknown"


def _rss_bytes() -> int:
    try:
        with open("/proc/self/statm", encoding="ascii") as statm:
            return int(statm.read().split()[1]) * _PAGE_BYTES
    except (OSError, ValueError, IndexError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # the peak, where /proc is missing


@dataclass(frozen=True)
class ProcessFacts:
    cpu_percent: float
    rss_bytes: int
    uptime_s: float
    version: str
    pid: int
    restartable: bool
    restarts: int
    log_tail: list[str]


class ProcessWatch:
    """The process's facts, and its restart when it runs on its own (restarter set by `python -m skill_server`)."""

    def __init__(self, restarter: Callable[[], None] | None = None, restarts: int = 0) -> None:
        self._restarter, self.restarts = restarter, restarts
        self._started_s = time.monotonic()
        self._lock = threading.Lock()
        self._last = (self._started_s, time.process_time())
        self._tail = log_tail()

    @property
    def restartable(self) -> bool:
        return self._restarter is not None

    def facts(self) -> ProcessFacts:
        """CPU since the previous reading (or the start), memory now, and the rest."""
        now, cpu = time.monotonic(), time.process_time()
        with self._lock:
            (then, cpu_then), self._last = self._last, (now, cpu)
        percent = 100.0 * (cpu - cpu_then) / (now - then) if now > then else 0.0
        return ProcessFacts(round(percent, 1), _rss_bytes(), now - self._started_s, version(), os.getpid(),
                            self.restartable, self.restarts, self._tail.lines())

    def restart(self) -> bool:
        """Asks the process to start again (after this answer); False when it runs inside another program."""
        if self._restarter is None:
            return False
        logging.getLogger(__name__).warning("restart requested from the web; the robot starts again")
        self._restarter()
        return True


def exec_again(arguments: Sequence[str], controller_token: str, restarts: int) -> None:
    """Replaces this process by a fresh skill server with arguments (same pid: its supervisor sees it go on)."""
    environment = {**os.environ, CONTROLLER_TOKEN_VARIABLE: controller_token, RESTARTS_VARIABLE: str(restarts)}
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, [sys.executable, "-m", "skill_server", *arguments], environment)
