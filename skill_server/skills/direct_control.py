"""The direct_control skill: the controller sets the base's velocities, guarded by a deadman."""

from __future__ import annotations

from skill_server.goals import GoalFeedback
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for, succeeded
from skill_server.skills.schema import ParameterSchema, ParameterType, SkillDescription

DIRECT_CONTROL = "direct_control"
DIRECT_GOAL_MAX_S = 10.0  # a goal is a short move; steady teleoperation goes through Drive and its deadman


def direct_control_description(spec: RobotSpec) -> SkillDescription:
    """The schema of direct_control for a robot with the given limits."""
    return SkillDescription(
        name=DIRECT_CONTROL,
        title="Direct control",
        help=(
            "Drive the base with linear and angular velocities. Send commands continuously: "
            "the base stops when they stop arriving for the deadman timeout. Activated as a goal, it holds "
            "the velocities for duration_s and then stops."
        ),
        parameters=(
            ParameterSchema(
                name="linear_mps",
                type=ParameterType.DOUBLE,
                unit="m/s",
                minimum=-spec.max_linear_mps,
                maximum=spec.max_linear_mps,
                default=0.0,
                help="Forward speed; negative drives backwards.",
            ),
            ParameterSchema(
                name="angular_radps",
                type=ParameterType.DOUBLE,
                unit="rad/s",
                minimum=-spec.max_angular_radps,
                maximum=spec.max_angular_radps,
                default=0.0,
                help="Turn rate; positive turns left (counter-clockwise).",
            ),
            ParameterSchema(
                name="duration_s",
                type=ParameterType.DOUBLE,
                unit="s",
                minimum=0.0,
                maximum=DIRECT_GOAL_MAX_S,
                default=1.0,
                help="As a goal: how long to hold the velocities before stopping (Drive commands ignore it).",
            ),
        ),
    )


def validate_velocity_command(spec: RobotSpec, linear_mps: object, angular_radps: object) -> tuple[float, float]:
    """Checks a drive command against the schema; returns (linear_mps, angular_radps) or raises."""
    description = direct_control_description(spec)
    linear = description.parameter("linear_mps").validate(linear_mps)
    angular = description.parameter("angular_radps").validate(angular_radps)
    assert isinstance(linear, float) and isinstance(angular, float)
    return linear, angular


class DirectControl(SkillController):
    """Holds the given velocities for duration_s, then stops and succeeds."""

    def __init__(self, linear_mps: float, angular_radps: float, duration_s: float) -> None:
        super().__init__()
        self._linear_mps = linear_mps
        self._angular_radps = angular_radps
        self._duration_s = duration_s
        self._started_s: float | None = None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Drives until the duration has passed."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        elapsed_s = tick.sim_time_s - self._started_s
        progress = elapsed_s / self._duration_s if self._duration_s > 0 else 1.0
        feedback = feedback_for(tick, "driving", progress, remaining_s=max(0.0, self._duration_s - elapsed_s))
        if elapsed_s >= self._duration_s:
            return 0.0, 0.0, succeeded(f"drove for {self._duration_s:g} s"), feedback
        return self._linear_mps, self._angular_radps, None, feedback
