"""A process's CPU share and memory, read from /proc (Linux), for a farm's load figures."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

_TICKS_PER_S = os.sysconf("SC_CLK_TCK")
_PAGE_MB = os.sysconf("SC_PAGE_SIZE") / 2**20


def cpu_seconds(pid: int) -> float | None:
    """User and system CPU time of pid so far (children not included); None when it has gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / _TICKS_PER_S  # utime, stime (fields 14 and 15 of stat)


def resident_mb(pid: int) -> float | None:
    """Resident memory of pid in MB; None when it has gone."""
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * _PAGE_MB
    except OSError:
        return None


@dataclass
class CpuMeter:
    """The share of one core a process used between two looks."""

    _last: dict[int, tuple[float, float]] = field(default_factory=dict)

    def share(self, pid: int) -> float | None:
        """CPU share of pid since the previous look at it; None on the first look or when it has gone."""
        used, now = cpu_seconds(pid), time.monotonic()
        if used is None:
            self._last.pop(pid, None)
            return None
        previous = self._last.get(pid)
        self._last[pid] = (used, now)
        if previous is None or now <= previous[1]:
            return None
        return (used - previous[0]) / (now - previous[1])
