"""The registry of skills a robot offers, in the order ListSkills reports them."""

from __future__ import annotations

from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.schema import SkillDescription


class SkillRegistry:
    """Skills by name; later issues add go-to-goal, orientation, and the perceptive skills here."""

    def __init__(self) -> None:
        self._skills: dict[str, SkillDescription] = {}

    def register(self, description: SkillDescription) -> None:
        """Adds a skill; a second skill of the same name is a programming error."""
        if description.name in self._skills:
            raise ValueError(f"skill {description.name!r} is already registered")
        self._skills[description.name] = description

    def get(self, name: str) -> SkillDescription:
        """The skill registered under name (KeyError if none)."""
        return self._skills[name]

    def descriptions(self) -> list[SkillDescription]:
        """Every registered skill, in registration order."""
        return list(self._skills.values())


def default_registry(spec: RobotSpec) -> SkillRegistry:
    """The skills every Telelab robot offers, with limits taken from its spec."""
    from skill_server.skills.direct_control import direct_control_description

    registry = SkillRegistry()
    registry.register(direct_control_description(spec))
    return registry
