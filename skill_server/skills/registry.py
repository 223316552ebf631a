"""The registry of skills a robot offers, in the order ListSkills reports them, with their builders."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from skill_server.errors import UnknownSkill
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import SkillController
from skill_server.skills.schema import SkillDescription

# Builds a controller from validated parameters and the sequencer's shared perception data.
SkillBuilder = Callable[[dict[str, Any], Any], SkillController]


@dataclass(frozen=True)
class SkillEntry:
    """A skill's schema, whether it drives the wheels, and how to build its controller."""

    description: SkillDescription
    motor: bool
    build: SkillBuilder | None


class SkillRegistry:
    """Skills by name."""

    def __init__(self) -> None:
        self._skills: dict[str, SkillEntry] = {}

    def register(self, description: SkillDescription, build: SkillBuilder | None = None, motor: bool = True) -> None:
        """Adds a skill; a second skill of the same name is a programming error."""
        if description.name in self._skills:
            raise ValueError(f"skill {description.name!r} is already registered")
        self._skills[description.name] = SkillEntry(description, motor, build)

    def get(self, name: str) -> SkillDescription:
        """The skill registered under name (KeyError if none)."""
        return self._skills[name].description

    def entry(self, name: str) -> SkillEntry:
        """The whole entry of a skill, or UnknownSkill naming the known ones."""
        try:
            return self._skills[name]
        except KeyError:
            raise UnknownSkill(name, list(self._skills)) from None

    def descriptions(self) -> list[SkillDescription]:
        """Every registered skill, in registration order."""
        return [entry.description for entry in self._skills.values()]


def default_registry(spec: RobotSpec) -> SkillRegistry:
    """The skills every Telelab robot offers, with limits taken from its spec."""
    from skill_server.skills import catalog

    registry = SkillRegistry()
    catalog.register_all(registry, spec)
    return registry
