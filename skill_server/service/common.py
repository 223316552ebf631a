"""Helpers every part of the adapter shares: aborting with a status, stream rates, sim-time pacing."""

from __future__ import annotations

import math
from typing import NoReturn

import grpc


class SimTimePacer:
    """Lets through one item per period of sim time, keeping the average rate when items come unevenly."""

    def __init__(self, period_s: float) -> None:
        self._period_s = period_s
        self._next_due_s: float | None = None
        self._last_s = -math.inf

    def due(self, sim_time_s: float) -> bool:
        """True if an item stamped sim_time_s should be sent (a sim-time restart makes it due at once)."""
        if sim_time_s < self._last_s:
            self._next_due_s = None
        self._last_s = sim_time_s
        if self._next_due_s is not None and sim_time_s + 1e-9 < self._next_due_s:
            return False
        behind = self._next_due_s is None or sim_time_s - self._next_due_s >= self._period_s
        self._next_due_s = sim_time_s + self._period_s if behind else self._next_due_s + self._period_s
        return True


def abort(context: grpc.ServicerContext, code: grpc.StatusCode, message: str) -> NoReturn:
    context.abort(code, message)
    raise AssertionError("context.abort always raises")


def stream_rate(
    context: grpc.ServicerContext, field: str, requested: float, default: float, maximum: float, unit: str
) -> float:
    if requested == 0:
        return default
    if not math.isfinite(requested) or not 0 < requested <= maximum:
        abort(
            context,
            grpc.StatusCode.INVALID_ARGUMENT,
            f"{field} must be a finite number above 0 and at most {maximum:g} {unit} (0 means {default:g})",
        )
    return requested


