"""The orientation_control skill: turn on the spot to a heading within a tolerance."""

from __future__ import annotations

import math

from skill_server.goals import EventKind, GoalFeedback
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import (
    HeadingController,
    Outcome,
    SkillController,
    TickInput,
    aborted,
    feedback_for,
    heading_error,
    succeeded,
)

ORIENTATION_CONTROL = "orientation_control"
SETTLED_RADPS = 0.05  # the turn counts as finished once the base has nearly stopped turning


def orientation_description(spec: RobotSpec) -> SkillDescription:
    """The schema of orientation_control."""
    return SkillDescription(
        name=ORIENTATION_CONTROL,
        title="Orientation control",
        help="Turn on the spot to a heading of the lab frame and stop within the tolerance.",
        parameters=(
            ParameterSchema("heading_rad", ParameterType.DOUBLE, "rad", -math.pi, math.pi, 0.0,
                            "Target heading, counter-clockwise from the lab's +x axis."),
            ParameterSchema("tolerance_rad", ParameterType.DOUBLE, "rad", 0.005, 0.5, 0.02,
                            "The heading counts as reached within this error."),
            ParameterSchema("max_angular_radps", ParameterType.DOUBLE, "rad/s", 0.1, spec.max_angular_radps, 1.0,
                            "Fastest turn rate."),
            ParameterSchema("timeout_s", ParameterType.DOUBLE, "s", 1.0, 600.0, 30.0,
                            "Abort with TIMEOUT after this much time."),
        ),
    )


class OrientationControl(SkillController):
    """Proportional turn to a heading; succeeds once within tolerance and settled."""

    skill_class = "sensorimotor"  # chooses its wheel commands from what the sensors report

    def __init__(self, heading_rad: float, tolerance_rad: float, max_angular_radps: float, timeout_s: float) -> None:
        super().__init__()
        self.heading_rad = heading_rad
        self._tolerance_rad = tolerance_rad
        self._timeout_s = timeout_s
        self._controller = HeadingController(max_angular_radps=max_angular_radps)
        self._started_s: float | None = None
        self._start_error_rad = 0.0

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Turns toward the heading; stops inside the tolerance."""
        error = heading_error(self.heading_rad, tick.pose)
        if self._started_s is None:
            self._started_s = tick.sim_time_s
            self._start_error_rad = max(abs(error), 1e-6)
        progress = 1.0 - abs(error) / self._start_error_rad
        if abs(error) <= self._tolerance_rad:
            feedback = feedback_for(tick, "settling", progress, 0.0, error)
            if abs(tick.odometry.angular_radps) < SETTLED_RADPS:
                self.announce(EventKind.GOAL_REACHED, f"heading reached, {math.degrees(error):.2f} deg off")
                return 0.0, 0.0, succeeded(f"turned to within {math.degrees(abs(error)):.2f} deg"), feedback
            return 0.0, 0.0, None, feedback
        if tick.sim_time_s - self._started_s > self._timeout_s:
            return 0.0, 0.0, aborted("TIMEOUT", f"gave up after {self._timeout_s:g} s, "
                                     f"{math.degrees(error):.1f} deg from the heading"), feedback_for(
                tick, "timeout", progress, 0.0, error)
        return 0.0, self._controller.command(error), None, feedback_for(tick, "turning", progress, 0.0, error)
