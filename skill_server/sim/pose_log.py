"""What the robot did, kept by the robot: its true and odometric pose a few times a second, with the wall clock.

An experimental attempt is graded on the robot's run between the attempt's start and its submission; kept here,
the run is complete whichever web worker asks for it, and whether or not the one that started the attempt is
still alive. Appended by the world's loop; read by gRPC handlers.
"""

from __future__ import annotations

import threading
from collections import deque

from skill_server.errors import InvalidParameter
from skill_server.sim.pacing import SimTimePacer
from skill_server.sim.snapshots import RobotSnapshot

RATE_HZ = 5.0
KEEP_S = 3 * 3600.0  # longer than any test's duration (tutors set at most two hours)
MAX_SAMPLES_PER_READ = 60_000

Sample = tuple[float, float, float, float, float, float, float]  # unix_s, gx, gy, gth, ox, oy, oth


class PoseLog:
    """The last KEEP_S of samples at RATE_HZ."""

    def __init__(self, rate_hz: float = RATE_HZ, keep_s: float = KEEP_S) -> None:
        self._pacer = SimTimePacer(1.0 / rate_hz)  # on the wall clock: the rate holds when ticks come unevenly
        self._samples: deque[Sample] = deque(maxlen=int(keep_s * rate_hz))
        self._lock = threading.Lock()

    def note(self, snapshot: RobotSnapshot) -> None:
        """Keeps the snapshot's poses when the next sample is due (the loop's thread)."""
        at = snapshot.capture_unix_s
        with self._lock:
            if not self._pacer.due(at):
                return
            truth, odometry = snapshot.ground_truth, snapshot.odometry.pose
            self._samples.append((at, truth.x_m, truth.y_m, truth.theta_rad, odometry.x_m, odometry.y_m,
                                  odometry.theta_rad))

    def between(self, from_unix_s: float, to_unix_s: float) -> tuple[list[Sample], float | None]:
        """The samples in [from, to] and the time of the oldest one kept (None: none yet)."""
        if not (from_unix_s == from_unix_s and to_unix_s == to_unix_s) or from_unix_s > to_unix_s:  # NaN, order
            raise InvalidParameter("from_unix_s", "from_unix_s must be a time at or before to_unix_s")
        with self._lock:
            oldest = self._samples[0][0] if self._samples else None
            chosen = [s for s in self._samples if from_unix_s <= s[0] <= to_unix_s]
        return chosen[-MAX_SAMPLES_PER_READ:], oldest
