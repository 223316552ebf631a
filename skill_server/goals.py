"""Goals: the lifecycle of one skill activation (ROS 2 action semantics) and the book that keeps them."""

from __future__ import annotations

import enum
import itertools
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

from skill_server.sim.geometry import Pose2D

RETAINED_FINISHED_GOALS = 200  # finished goals kept for GetGoal/WatchGoal after their end
MAX_EVENTS_PER_GOAL = 500  # a runaway skill must not grow a goal's log without bound
PLANNED_PATH_POINTS = 64  # feedback carries at most this many waypoints: each watcher gets them at 10 Hz


class GoalStatus(enum.Enum):
    """Where a goal is in its life; the last three are terminal."""

    ACCEPTED = "accepted"
    EXECUTING = "executing"
    CANCELING = "canceling"
    SUCCEEDED = "succeeded"
    CANCELED = "canceled"
    ABORTED = "aborted"

    @property
    def is_terminal(self) -> bool:
        """True once the goal can change no more."""
        return self in (GoalStatus.SUCCEEDED, GoalStatus.CANCELED, GoalStatus.ABORTED)


class EventKind(enum.Enum):
    """Things a skill announces to its watchers."""

    STARTED = "started"
    STEP_STARTED = "step_started"  # moved on to its next step (a complex skill's next simple skill, a search)
    OBSTACLE_DETECTED = "obstacle_detected"
    PATH_REPLANNED = "path_replanned"
    CONVERGED = "converged"
    GOAL_REACHED = "goal_reached"
    FAILED = "failed"
    CANCELED = "canceled"
    PREEMPTED = "preempted"
    WALL_LOST = "wall_lost"  # wall following lost its wall
    BATTERY_LOW = "battery_low"  # a plan's battery watch saw the charge fall below its threshold
    HANDLED = "handled"  # a plan's `on` block started: the event and the line it cut short


@dataclass(frozen=True)
class GoalEvent:
    """One announcement, stamped with sim time."""

    sim_time_s: float
    kind: EventKind
    message: str


@dataclass(frozen=True)
class GoalFeedback:
    """What a running skill reports each tick (watchers see the latest at their rate)."""

    sim_time_s: float = 0.0
    state: str = ""
    progress: float = 0.0  # [0, 1]
    distance_error_m: float = 0.0
    heading_error_rad: float = 0.0
    pose: Pose2D = field(default_factory=Pose2D)  # the pose the skill believes (odometry or localization)
    pose_source: str = "odometry"
    values: tuple[tuple[str, float], ...] = ()  # skill-specific figures, e.g. ("wall_distance_m", 0.5)
    planned_path: tuple[tuple[float, float], ...] = ()  # waypoints still ahead (x_m, y_m), lab frame (go-to-goal)


def capped_path(path: tuple[tuple[float, float], ...],
                limit: int = PLANNED_PATH_POINTS) -> tuple[tuple[float, float], ...]:
    """The path with at most limit waypoints: a longer one thinned evenly, keeping its first and its last (the goal)."""
    if len(path) <= limit:
        return path
    step = (len(path) - 1) / (limit - 1)
    return tuple(path[round(index * step)] for index in range(limit))


@dataclass(frozen=True)
class GoalSnapshot:
    """A goal's whole state at one moment: what GetGoal answers and WatchGoal ends with."""

    goal_id: str
    skill: str
    motor: bool
    status: GoalStatus
    parameters: tuple[tuple[str, float | int | bool | str], ...]
    accepted_sim_s: float
    ended_sim_s: float | None
    error_code: str  # "" on success; ABORTED: TIMEOUT, UNREACHABLE, ...; CANCELED: CANCELED, PREEMPTED
    message: str
    feedback: GoalFeedback
    goal_reached: bool
    event_count: int
    feedback_version: int


class Goal:
    """One activation's mutable record; the loop writes it, any thread reads it through snapshot()."""

    def __init__(
        self,
        book: GoalBook,
        goal_id: str,
        skill: str,
        motor: bool,
        parameters: dict[str, float | int | bool | str],
        sim_time_s: float,
    ) -> None:
        self._book = book
        self.goal_id = goal_id
        self.skill = skill
        self.motor = motor
        self.parameters = dict(parameters)
        self.accepted_sim_s = sim_time_s
        self.ended_sim_s: float | None = None
        self.status = GoalStatus.ACCEPTED
        self.error_code = ""
        self.message = ""
        self.goal_reached = False
        self.feedback = GoalFeedback(sim_time_s=sim_time_s, state="accepted")
        self.feedback_version = 0
        self.events: list[GoalEvent] = []
        self.cancel_requested = False

    def snapshot(self) -> GoalSnapshot:
        """A frozen copy of the goal's state."""
        with self._book.changed:
            return GoalSnapshot(
                goal_id=self.goal_id,
                skill=self.skill,
                motor=self.motor,
                status=self.status,
                parameters=tuple(sorted(self.parameters.items())),
                accepted_sim_s=self.accepted_sim_s,
                ended_sim_s=self.ended_sim_s,
                error_code=self.error_code,
                message=self.message,
                feedback=self.feedback,
                goal_reached=self.goal_reached,
                event_count=len(self.events),
                feedback_version=self.feedback_version,
            )

    def events_since(self, index: int) -> list[GoalEvent]:
        """Events from position index on."""
        with self._book.changed:
            return self.events[index:]

    def set_status(self, status: GoalStatus) -> None:
        """Moves a live goal to ACCEPTED/EXECUTING/CANCELING."""
        with self._book.changed:
            if not self.status.is_terminal:
                self.status = status
                self._book.changed.notify_all()

    def announce(self, sim_time_s: float, kind: EventKind, message: str) -> None:
        """Appends an event and wakes the watchers."""
        with self._book.changed:
            if len(self.events) < MAX_EVENTS_PER_GOAL:
                self.events.append(GoalEvent(sim_time_s, kind, message))
            self._book.changed.notify_all()

    def report(self, feedback: GoalFeedback) -> None:
        """Replaces the latest feedback and wakes the watchers."""
        with self._book.changed:
            self.feedback = feedback
            self.feedback_version += 1
            self._book.changed.notify_all()

    def finish(
        self, status: GoalStatus, sim_time_s: float, error_code: str, message: str, reached: bool = False
    ) -> bool:
        """Ends the goal once; returns False if it had already ended."""
        assert status.is_terminal
        with self._book.changed:
            if self.status.is_terminal:
                return False
            self.status = status
            self.ended_sim_s = sim_time_s
            self.error_code = error_code
            self.message = message
            self.goal_reached = reached
            self._book.changed.notify_all()
        self._book.retire(self)
        return True


class GoalBook:
    """Every live goal and the last finished ones, with one condition that wakes watchers on any change."""

    def __init__(self, retained: int = RETAINED_FINISHED_GOALS) -> None:
        self.changed = threading.Condition()
        self._retained = retained
        self._goals: OrderedDict[str, Goal] = OrderedDict()
        self._finished: list[str] = []
        self._ids = itertools.count(1)
        self._closed = False

    def create(
        self, skill: str, motor: bool, parameters: dict[str, float | int | bool | str], sim_time_s: float
    ) -> Goal:
        """A new ACCEPTED goal with a fresh id."""
        with self.changed:
            goal_id = f"goal-{next(self._ids)}"
            goal = Goal(self, goal_id, skill, motor, parameters, sim_time_s)
            self._goals[goal_id] = goal
            self.changed.notify_all()
            return goal

    def get(self, goal_id: str) -> Goal | None:
        """The goal with that id, live or retained; None if unknown or forgotten."""
        with self.changed:
            return self._goals.get(goal_id)

    def all(self) -> list[Goal]:
        """Every known goal, oldest first."""
        with self.changed:
            return list(self._goals.values())

    def retire(self, goal: Goal) -> None:
        """Records that goal finished, forgetting the oldest finished goals beyond the retention."""
        with self.changed:
            self._finished.append(goal.goal_id)
            while len(self._finished) > self._retained:
                self._goals.pop(self._finished.pop(0), None)

    def close(self) -> None:
        """Wakes every watcher for good (the server is stopping)."""
        with self.changed:
            self._closed = True
            self.changed.notify_all()

    @property
    def closed(self) -> bool:
        """True once the server stopped."""
        return self._closed

    def wait(self, predicate_timeout_s: float, predicate: Callable[[], bool]) -> None:
        """Blocks until predicate() is true, the book closes, or the timeout passes."""
        with self.changed:
            self.changed.wait_for(lambda: self._closed or predicate(), predicate_timeout_s)

    def wake(self) -> None:
        """Wakes every watcher so it can re-check its cancel flag."""
        with self.changed:
            self.changed.notify_all()
