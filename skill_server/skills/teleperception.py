"""Teleperception: the robot's readings gathered into its evidence grid while someone watches, and kept raw.

The world's loop hands every published snapshot to `observe`; while nobody has asked for the grid in the last
WATCH_S seconds that is one comparison, so an unwatched robot pays nothing. Every reading is placed at the
odometry pose of its snapshot (never the ground truth: a student must not be handed the truth) and filed under
the part it belongs to, "static" while the robot stands and "moving" while it drives. The grid lives on the
robot, so every viewer (the student, observers, a tutor) sees the same one.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from skill_server.sim.geometry import Pose2D
from skill_server.sim.snapshots import RobotSnapshot
from skill_server.skills.environment_model import PublishedGrid
from skill_server.skills.evidence_grid import PARTS, SENSORS, EvidenceGrid

WATCH_S = 10.0  # [s] of wall-clock time a read keeps the grid accumulating
MIN_PERIOD_S = 0.1  # [s] of sim time between readings integrated (10 Hz; sensors are read at 20 Hz)
MAX_KEPT_SCANS = 2400  # raw readings kept for export: 4 minutes at 10 Hz
MAX_SCANS_PER_ANSWER = 600  # about 0.5 MB: a reader pages through the rest with after_index
MOVING_MPS, TURNING_RADPS = 0.01, 0.03  # odometry's speeds above which a reading belongs to the moving part


@dataclass(frozen=True)
class PerceptionScan:
    """One reading of both sensors, as integrated: where odometry put the robot, when, and in which part."""

    index: int
    capture_unix_s: float
    sim_time_s: float
    odometry: Pose2D
    part: str
    sonar_ranges_m: tuple[float, ...]
    laser_ranges_m: tuple[float, ...]


@dataclass(frozen=True)
class EvidenceState:
    """The chosen layers of the grid with the counts of readings integrated so far."""

    view: PublishedGrid  # scans_integrated: readings of both sensors; sim_time_s: of the last one
    scans_by_sensor: dict[str, int]
    scans_by_part: dict[str, int]
    accumulating: bool
    version: int


class Teleperception:
    """The evidence grid, its counts and the raw readings; observe() runs in the loop, the rest anywhere."""

    def __init__(self, grid: EvidenceGrid, clock: Callable[[], float] = time.monotonic) -> None:
        self._grid = grid
        self._clock = clock
        self._lock = threading.Lock()
        self._watch_until = -1.0
        self._last_laser: tuple[float, ...] | None = None
        self._last_sim_s = -1.0
        self._scans: deque[PerceptionScan] = deque(maxlen=MAX_KEPT_SCANS)
        self._next_index = 1
        self._by_sensor = dict.fromkeys(SENSORS, 0)
        self._by_part = dict.fromkeys(PARTS, 0)
        self._version = 0

    def watch(self) -> None:
        """Someone reads the grid: keep accumulating for WATCH_S more."""
        self._watch_until = self._clock() + WATCH_S

    @property
    def accumulating(self) -> bool:
        """Whether readings are integrated now."""
        return self._clock() < self._watch_until

    def observe(self, snapshot: RobotSnapshot) -> None:
        """Integrates the snapshot's readings if someone watches and they are new (the world's loop calls this)."""
        if not self.accumulating or snapshot.laser_ranges_m is self._last_laser:
            return
        if 0 <= snapshot.sim_time_s - self._last_sim_s < MIN_PERIOD_S - 1e-9:
            return
        self._last_laser, self._last_sim_s = snapshot.laser_ranges_m, snapshot.sim_time_s
        odometry = snapshot.odometry
        moving = abs(odometry.linear_mps) > MOVING_MPS or abs(odometry.angular_radps) > TURNING_RADPS
        part = "moving" if moving else "static"
        with self._lock:
            if snapshot.sonar_ranges_m:
                self._grid.add_sonar(odometry.pose, snapshot.sonar_ranges_m, part)
                self._by_sensor["sonar"] += 1
            if snapshot.laser_ranges_m:
                self._grid.add_laser(odometry.pose, snapshot.laser_ranges_m, part)
                self._by_sensor["laser"] += 1
            self._by_part[part] += 1
            self._scans.append(PerceptionScan(self._next_index, snapshot.capture_unix_s, snapshot.sim_time_s,
                                              odometry.pose, part, snapshot.sonar_ranges_m,
                                              snapshot.laser_ranges_m))
            self._next_index += 1
            self._version += 1

    def state(self, sensors: tuple[str, ...] = SENSORS, parts: tuple[str, ...] = PARTS) -> EvidenceState:
        """The sum of the chosen layers and the counts."""
        with self._lock:
            view = self._grid.view(sensors, parts, sum(self._by_part.values()), max(0.0, self._last_sim_s))
            return EvidenceState(view, dict(self._by_sensor), dict(self._by_part), self.accumulating, self._version)

    def reset(self) -> None:
        """Forgets the evidence, the counts and the readings kept (their numbering goes on)."""
        with self._lock:
            self._grid.clear()
            self._scans.clear()
            self._by_sensor = dict.fromkeys(SENSORS, 0)
            self._by_part = dict.fromkeys(PARTS, 0)
            self._version += 1

    def scans_after(self, index: int, limit: int = MAX_SCANS_PER_ANSWER) -> list[PerceptionScan]:
        """The oldest limit readings kept (the last MAX_KEPT_SCANS since the last reset) numbered above index."""
        with self._lock:
            return list(itertools.islice((scan for scan in self._scans if scan.index > index), limit))
