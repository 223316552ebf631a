"""The direct_control skill: the controller sets the base's velocities, guarded by a deadman."""

from __future__ import annotations

from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.schema import ParameterSchema, ParameterType, SkillDescription

DIRECT_CONTROL = "direct_control"


def direct_control_description(spec: RobotSpec) -> SkillDescription:
    """The schema of direct_control for a robot with the given limits."""
    return SkillDescription(
        name=DIRECT_CONTROL,
        title="Direct control",
        help=(
            "Drive the base with linear and angular velocities. Send commands continuously: "
            "the base stops when they stop arriving for the deadman timeout."
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
        ),
    )


def validate_velocity_command(spec: RobotSpec, linear_mps: object, angular_radps: object) -> tuple[float, float]:
    """Checks a drive command against the schema; returns (linear_mps, angular_radps) or raises."""
    description = direct_control_description(spec)
    linear = description.parameter("linear_mps").validate(linear_mps)
    angular = description.parameter("angular_radps").validate(angular_radps)
    assert isinstance(linear, float) and isinstance(angular, float)
    return linear, angular
