"""The direct_control skill: the controller sets the base's velocities, guarded by a deadman."""

from __future__ import annotations

from skill_server.goals import GoalFeedback
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.drive_gate import velocity_parameters
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for, succeeded

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
            *velocity_parameters(spec),
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


class DirectControl(SkillController):
    """Holds the given velocities for duration_s, then stops and succeeds."""

    direct_drive = True

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
