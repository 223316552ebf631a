"""The controllers of a plan's own lines (timed drives, waits, settings, messages) and its conditions.

Skill lines run the skill's own controller, built by the registry as ActivateSkill builds it (executor.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from skill_server.goals import GoalFeedback
from skill_server.plans.model import PlanCondition
from skill_server.plans.validation import BATTERY_FIELD
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, aborted, feedback_for, succeeded
from skill_server.skills.go_to_goal import STOP_CLEARANCE_M
from skill_server.skills.obstacles import clearance

GUARD_MARGIN_M = 0.02  # beyond the braking distance: the robot stops short of what its sensors see


@dataclass
class PlanSettings:
    """What `set` lines changed; they last until the plan ends."""

    max_linear_mps: float
    max_angular_radps: float


@dataclass(frozen=True)
class WatchdogChange:
    """A plan's `set watchdog`: the controller it was set for, the value it replaced and the value it set."""

    token: str
    previous_s: float
    set_s: float


class DriveWatchdog(Protocol):
    """The base's drive watchdog (the deadman timeout of direct drive commands, as SetLimits sets it), as a plan
    sets it for its controller and gives it back; called in the world's loop thread."""

    def change(self, watchdog_s: float, previous: WatchdogChange | None) -> WatchdogChange | None:
        """Sets the watchdog for the controller in force (previous: the plan's earlier change, whose replaced
        value is kept); None when nobody controls the robot."""

    def restore(self, change: WatchdogChange) -> None:
        """Gives back the value the plan replaced, unless the controller or the watchdog changed since."""


LINE_SEEN = 0.5  # a line sensor cell reading above this sees the tape


def condition_holds(condition: PlanCondition, tick: TickInput, goal_reached: bool) -> bool:
    """Evaluates a checked condition on this tick's readings."""
    if condition.kind == "obstacle_within":
        holds = nearest_obstacle_m(tick) <= condition.value
    elif condition.kind == "goal_reached":
        holds = goal_reached
    elif condition.kind == "line_seen":  # a cell of the line sensor over the tape
        holds = any(value > LINE_SEEN for value in tick.line_readings)
    else:  # battery_below: validation let it through only when the tick carries a battery
        charge = getattr(tick, BATTERY_FIELD, None)
        holds = charge is not None and float(charge) < condition.value
    return holds != condition.negate


def nearest_obstacle_m(tick: TickInput) -> float:
    """The nearest echo of the laser or a sonar, from the robot's rim [m]."""
    free = clearance(tick)
    laser = [r for r in tick.laser_ranges_m if r < tick.sensors.laser.max_range_m - 1e-6]
    laser_m = min(laser) - tick.spec.body_radius_m if laser else math.inf
    return max(0.0, min(free.nearest_m, free.ahead_m, laser_m))


def describe_condition(condition: PlanCondition) -> str:
    """A condition as the plan's text writes it."""
    value = "" if condition.kind in ("goal_reached", "line_seen") else f" {condition.value:g}"
    return f"{'not ' if condition.negate else ''}{condition.kind}{value}"


def braking_distance_m(spec: RobotSpec, speed_mps: float) -> float:
    """How far the base rolls while its acceleration limit brings it to a stop."""
    return speed_mps * speed_mps / (2.0 * spec.max_linear_accel_mps2)


class TimedDrive(SkillController):
    """Holds wheel velocities for a time; stops and fails COLLISION_AHEAD before touching what it sees."""

    def __init__(self, linear_mps: float, angular_radps: float, duration_s: float) -> None:
        super().__init__()
        self._linear_mps, self._angular_radps, self._duration_s = linear_mps, angular_radps, duration_s
        self._started_s: float | None = None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Drives until the time is up or an obstacle comes within braking distance in the direction of travel."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        elapsed_s = tick.sim_time_s - self._started_s
        feedback = feedback_for(tick, "driving", elapsed_s / self._duration_s,
                                remaining_s=max(0.0, self._duration_s - elapsed_s))
        if elapsed_s >= self._duration_s - 1e-9:
            return 0.0, 0.0, succeeded(f"drove for {self._duration_s:g} s"), feedback
        if self._linear_mps != 0.0:
            free = clearance(tick)
            room_m = free.ahead_m if self._linear_mps > 0 else free.behind_m
            # The speed it may have by the next reading: what it has now plus one tick's acceleration.
            speed_mps = abs(tick.odometry.linear_mps) + tick.spec.max_linear_accel_mps2 * tick.dt_s
            if room_m < STOP_CLEARANCE_M + GUARD_MARGIN_M + braking_distance_m(tick.spec, speed_mps):
                where = "ahead" if self._linear_mps > 0 else "behind"
                return 0.0, 0.0, aborted("COLLISION_AHEAD", f"stopped: an obstacle {room_m:.2f} m {where}"), feedback
        return self._linear_mps, self._angular_radps, None, feedback


class Wait(SkillController):
    """Stands still until the condition holds, or for the duration; with both, TIMEOUT when it never held."""

    def __init__(self, condition: PlanCondition | None, duration_s: float,
                 goal_reached: Callable[[], bool]) -> None:
        super().__init__()
        self._condition, self._duration_s, self._goal_reached = condition, duration_s, goal_reached
        self._started_s: float | None = None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Checks the condition every tick."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        elapsed_s = tick.sim_time_s - self._started_s
        timed = self._duration_s > 0
        feedback = feedback_for(tick, "waiting", elapsed_s / self._duration_s if timed else 0.0,
                                remaining_s=max(0.0, self._duration_s - elapsed_s) if timed else math.inf)
        if self._condition is not None and condition_holds(self._condition, tick, self._goal_reached()):
            return 0.0, 0.0, succeeded(f"{describe_condition(self._condition)} holds"), feedback
        if timed and elapsed_s >= self._duration_s - 1e-9:
            if self._condition is None:
                return 0.0, 0.0, succeeded(f"waited {self._duration_s:g} s"), feedback
            return 0.0, 0.0, aborted("TIMEOUT", f"{describe_condition(self._condition)} did not hold within "
                                                f"{self._duration_s:g} s"), feedback
        return 0.0, 0.0, None, feedback


class BatteryWatch:
    """A plan's watch of battery_low: fires when the charge falls below the threshold (at once when it is below
    already), and again only after it rose back to the threshold."""

    def __init__(self, threshold: float) -> None:
        self._threshold = threshold
        self._below = False

    def fired(self, tick: TickInput) -> str | None:
        """What it saw, in the tick the charge went below the threshold; None otherwise."""
        charge = float(getattr(tick, BATTERY_FIELD, 1.0))
        below = charge < self._threshold
        crossed, self._below = below and not self._below, below
        return f"battery at {charge:.0%}, below {self._threshold:.0%}" if crossed else None


class Instant(SkillController):
    """A line done in no time (a setting, a message): does its action on its first tick and succeeds."""

    def __init__(self, action: Callable[[], str]) -> None:
        super().__init__()
        self._action = action

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Acts once."""
        message = self._action()
        return 0.0, 0.0, succeeded(message), feedback_for(tick, "done", 1.0)
