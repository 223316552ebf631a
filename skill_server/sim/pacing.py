"""Pacing in sim time: streams and the camera send at most one item per period of simulated time."""

from __future__ import annotations

import math


class SimTimePacer:
    """Lets through one item per period of sim time, keeping the average rate when items come unevenly."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s  # may change between items (the camera follows its fastest viewer)
        self._next_due_s: float | None = None
        self._last_s = -math.inf

    def restart(self) -> None:
        """Makes the next item due at once."""
        self._next_due_s = None

    def due(self, sim_time_s: float) -> bool:
        """True if an item stamped sim_time_s should be sent (a sim-time restart makes it due at once)."""
        if sim_time_s < self._last_s:
            self._next_due_s = None
        self._last_s = sim_time_s
        next_due_s = self._next_due_s
        if next_due_s is None or sim_time_s - next_due_s >= self.period_s:  # first, or a period or more behind
            self._next_due_s = sim_time_s + self.period_s
        elif sim_time_s + 1e-9 < next_due_s:
            return False
        else:
            self._next_due_s = next_due_s + self.period_s
        return True
