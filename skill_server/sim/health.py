"""What a tutor reads to diagnose a robot from the web (the 2003 paper's telediagnosis): how the world's loop keeps up
with real time, and the faults the robot met, with their times.

The loop notes each tick; a reader asks for a report from any thread. Kept small and bounded: a few seconds of
samples, the last FAULTS_KEPT faults.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass

WINDOW_S = 5.0  # the real-time factor and the loop's lag are read over the last seconds
FAULTS_KEPT = 50


@dataclass(frozen=True)
class Fault:
    """Something that went wrong on the robot: when (wall clock), a stable kind, and a sentence."""

    unix_s: float
    kind: str
    message: str


@dataclass(frozen=True)
class LoopReport:
    """The loop over the last WINDOW_S: simulated seconds per wall second, and how far it fell behind real time."""

    real_time_factor: float
    lag_ms_p50: float
    lag_ms_max: float
    parked: bool


class LoopHealth:
    """Samples of the world's loop (wall time, sim time, lag) and the faults the robot recorded."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._samples: deque[tuple[float, float, float]] = deque()
        self._faults: deque[Fault] = deque(maxlen=FAULTS_KEPT)
        self._parked = False

    def note_tick(self, wall_s: float, sim_s: float, lag_s: float) -> None:
        """One tick of the loop (wall_s: time.monotonic())."""
        with self._lock:
            self._samples.append((wall_s, sim_s, max(0.0, lag_s)))
            self._parked = False
            while self._samples and wall_s - self._samples[0][0] > WINDOW_S:
                self._samples.popleft()

    def note_parked(self, parked: bool) -> None:
        """The robot at rest: the loop ticks in batches and has no lag to speak of."""
        with self._lock:
            self._parked = parked

    def fault(self, kind: str, message: str) -> None:
        with self._lock:
            self._faults.append(Fault(time.time(), kind, message))

    def faults(self) -> list[Fault]:
        """The faults kept, oldest first."""
        with self._lock:
            return list(self._faults)

    def report(self) -> LoopReport:
        with self._lock:
            samples, parked = list(self._samples), self._parked
        if len(samples) < 2:
            return LoopReport(1.0 if parked else 0.0, 0.0, 0.0, parked)
        (wall0, sim0, _), (wall1, sim1, _) = samples[0], samples[-1]
        factor = (sim1 - sim0) / (wall1 - wall0) if wall1 > wall0 else 0.0
        lags = sorted(lag for _, _, lag in samples)
        return LoopReport(factor, lags[len(lags) // 2] * 1000.0, lags[-1] * 1000.0, parked)
