"""Track runs (thesis chapter 4): arrival at A and B, contact with a border line, and the time of each run.

Pure logic over ground-truth poses and the scene's TrackSpec; the world loop calls observe() once a tick,
other threads read events() and state() (guarded by a lock). A line contact is an error: the run restarts
at A (the world puts the robot back) and the attempt's clock keeps running, as the thesis's operators had to
start again. restart() ends the attempt under way without a result (an experiment trial given up or begun), so
the next departure from A starts a new attempt timed from zero. No grpc and no pybullet here.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field

from skill_server.sim.geometry import Pose2D

MAX_EVENTS = 500


@dataclass(frozen=True)
class BorderLine:
    """A white line painted on the floor, as a segment with a half width [m]."""

    x1_m: float
    y1_m: float
    x2_m: float
    y2_m: float
    half_width_m: float = 0.025


@dataclass(frozen=True)
class TrackSpec:
    """A track: start A, goal B, whether the run comes back to A, and the border lines."""

    a_x_m: float
    a_y_m: float
    b_x_m: float
    b_y_m: float
    round_trip: bool
    arrival_radius_m: float = 0.35
    lines: tuple[BorderLine, ...] = ()
    body_radius_m: float = 0.20


@dataclass(frozen=True)
class TrackEvent:
    """Something that happened on the track: started, reached_b, reached_a, line_contact, finished, restarted."""

    index: int
    kind: str
    sim_time_s: float
    unix_s: float
    attempt: int
    elapsed_s: float
    errors: int
    message: str


@dataclass(frozen=True)
class TrackState:
    """Where the run is now, and the last finished attempt."""

    phase: str  # at_start | to_b | to_a | finished
    attempt: int
    elapsed_s: float
    errors: int
    last_attempt: int = 0
    last_total_time_s: float = 0.0
    last_errors: int = 0
    last_finished_unix_s: float = 0.0
    started_unix_s: float = 0.0  # wall clock when the present attempt started (0: none yet)
    last_started_unix_s: float = 0.0


def segment_distance_m(px: float, py: float, line: BorderLine) -> float:
    """Distance from a point to a line segment [m]."""
    dx, dy = line.x2_m - line.x1_m, line.y2_m - line.y1_m
    length_sq = dx * dx + dy * dy
    t = 0.0 if length_sq == 0 else max(0.0, min(1.0, ((px - line.x1_m) * dx + (py - line.y1_m) * dy) / length_sq))
    return math.hypot(px - (line.x1_m + t * dx), py - (line.y1_m + t * dy))


def touches_line(pose: Pose2D, track: TrackSpec) -> BorderLine | None:
    """The first border line the round body overlaps at pose, or None."""
    for line in track.lines:
        if segment_distance_m(pose.x_m, pose.y_m, line) < track.body_radius_m + line.half_width_m:
            return line
    return None


@dataclass
class TrackMonitor:
    """The run state machine of one track; observe() is the world loop's per-tick hook."""

    track: TrackSpec
    _phase: str = "at_start"
    _attempt: int = 0
    _started_sim_s: float = 0.0
    _started_unix_s: float = 0.0
    _elapsed_s: float = 0.0
    _errors: int = 0
    _last: tuple[int, float, int, float, float] = (0, 0.0, 0, 0.0, 0.0)
    _events: deque[TrackEvent] = field(default_factory=lambda: deque(maxlen=MAX_EVENTS))
    _count: int = 0
    _changed: threading.Condition = field(default_factory=threading.Condition)

    def _near(self, pose: Pose2D, x_m: float, y_m: float) -> bool:
        return math.hypot(pose.x_m - x_m, pose.y_m - y_m) <= self.track.arrival_radius_m

    def _emit(self, kind: str, sim_time_s: float, message: str) -> None:
        with self._changed:
            self._count += 1
            self._events.append(TrackEvent(self._count, kind, sim_time_s, time.time(), self._attempt,
                                           round(self._elapsed_s, 3), self._errors, message))
            self._changed.notify_all()

    def observe(self, pose: Pose2D, sim_time_s: float) -> bool:
        """Advances the run with the robot's true pose; True when the robot must go back to A (a line touched)."""
        track = self.track
        at_a = self._near(pose, track.a_x_m, track.a_y_m)
        if self._phase in ("at_start", "finished"):
            if not at_a and self._phase == "at_start":
                if self._attempt == 0 or self._last[0] == self._attempt:
                    self._attempt += 1
                    self._errors = 0
                    self._started_sim_s = sim_time_s
                    self._started_unix_s = time.time()
                self._phase = "to_b"
                self._emit("started", sim_time_s, f"Run {self._attempt} started: drive to B.")
            elif at_a and self._phase == "finished":
                self._phase = "at_start"
            return False
        self._elapsed_s = sim_time_s - self._started_sim_s
        if touches_line(pose, track) is not None:
            self._errors += 1
            self._phase = "at_start"
            self._emit("line_contact", sim_time_s, "The robot touched a white line: the run starts again at A.")
            return True
        if self._phase == "to_b" and self._near(pose, track.b_x_m, track.b_y_m):
            self._emit("reached_b", sim_time_s, "Reached B." + (" Now back to A." if track.round_trip else ""))
            if track.round_trip:
                self._phase = "to_a"
            else:
                self._finish(sim_time_s)
        elif self._phase == "to_a" and at_a:
            self._emit("reached_a", sim_time_s, "Back at A.")
            self._finish(sim_time_s)
        return False

    def _finish(self, sim_time_s: float) -> None:
        self._phase = "finished"
        self._last = (self._attempt, round(self._elapsed_s, 3), self._errors, time.time(), self._started_unix_s)
        self._emit("finished", sim_time_s, f"Finished in {self._elapsed_s:.1f} s with {self._errors} error(s).")

    def restart(self, sim_time_s: float) -> bool:
        """Ends the attempt under way without a result (the world loop's thread); False when none was under way.

        The attempt's number is given back, so the next departure from A starts it again from zero; until the
        robot is back at A, the phase is "finished" (a run begins at A).
        """
        if self._phase in ("at_start", "finished") and self._attempt == self._last[0]:
            return False
        given_up = self._attempt
        self._attempt, self._elapsed_s, self._errors = self._last[0], 0.0, 0
        self._started_sim_s, self._started_unix_s = 0.0, 0.0
        self._phase = "finished"
        self._emit("restarted", sim_time_s, f"Run {given_up} given up: drive to A (blue) to begin again.")
        return True

    def state(self) -> TrackState:
        """The present state (any thread)."""
        with self._changed:
            attempt, total, errors, finished, started = self._last
            return TrackState(self._phase, self._attempt, round(self._elapsed_s, 3), self._errors,
                              attempt, total, errors, finished, self._started_unix_s, started)

    def events_after(self, index: int, timeout_s: float) -> list[TrackEvent]:
        """Events numbered above index, waiting up to timeout_s for one (any thread)."""
        with self._changed:
            if self._count <= index:
                self._changed.wait(timeout_s)
            return [event for event in self._events if event.index > index]
