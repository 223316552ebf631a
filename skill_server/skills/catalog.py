"""Which skills a Telelab robot offers and how each is built from its validated parameters."""

from __future__ import annotations

from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.direct_control import DirectControl, direct_control_description
from skill_server.skills.go_to_goal import GoToGoal, go_to_goal_description
from skill_server.skills.localization import Localization, localization_description
from skill_server.skills.mapping import EnvironmentModelling, environment_modelling_description
from skill_server.skills.obstacles import DetectObstacle, detect_obstacle_description
from skill_server.skills.orientation import OrientationControl, orientation_description
from skill_server.skills.registry import SkillRegistry
from skill_server.skills.sequence import StepSequence, round_trip, round_trip_description
from skill_server.skills.wall_following import WallFollowing, wall_following_description


def register_all(registry: SkillRegistry, spec: RobotSpec) -> None:
    """Registers every skill, motor skills first, in the order panels should appear."""
    registry.register(direct_control_description(spec), DirectControl)
    registry.register(go_to_goal_description(spec), GoToGoal)
    registry.register(orientation_description(spec), OrientationControl)
    registry.register(wall_following_description(spec), WallFollowing)
    registry.register(round_trip_description(spec), StepSequence, lambda p, _: round_trip(**p))
    registry.register(detect_obstacle_description(), DetectObstacle)
    registry.register(environment_modelling_description(), EnvironmentModelling,
                      lambda p, perception: EnvironmentModelling(**p, perception=perception))
    registry.register(localization_description(), Localization,
                      lambda p, perception: Localization(**p, perception=perception))

def default_registry(spec: RobotSpec) -> SkillRegistry:
    """The skills every Telelab robot offers, with limits taken from its spec."""
    registry = SkillRegistry()
    register_all(registry, spec)
    return registry
