"""The registry of skills a robot offers, in the order ListSkills reports them, with their builders."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from skill_server.errors import UnknownSkill
from skill_server.schema import SkillDescription
from skill_server.skills.base import SkillController
from skill_server.skills.perception import Perception

# Builds a controller from validated parameters and the sequencer's shared perception data.
SkillBuilder = Callable[[dict[str, Any], Perception], SkillController]


@dataclass(frozen=True)
class SkillEntry:
    """A skill's schema, its controller class (whose declared traits it publishes) and how to build one."""

    description: SkillDescription
    skill: type[SkillController]
    build: SkillBuilder

    @property
    def motor(self) -> bool:
        """The skill drives the base (one motor goal at a time)."""
        return self.skill.motor

    @property
    def skill_class(self) -> str:
        """The 2003 paper's class of the skill: motor, perceptive, sensorimotor or deliberative."""
        return self.skill.skill_class

    @property
    def estimates_pose(self) -> bool:
        """While it runs, the other skills steer by its pose estimate."""
        return self.skill.estimates_pose

    @property
    def direct_drive(self) -> bool:
        """It does what Drive commands do, so consoles offer the drive pad for it."""
        return self.skill.direct_drive


class SkillRegistry:
    """Skills by name."""

    def __init__(self) -> None:
        self._skills: dict[str, SkillEntry] = {}

    def register(self, description: SkillDescription, skill: type[SkillController],
                 build: SkillBuilder | None = None) -> None:
        """Adds a skill built by build (default: skill(**parameters)); a second skill of the same name is an error."""
        if description.name in self._skills:
            raise ValueError(f"skill {description.name!r} is already registered")
        self._skills[description.name] = SkillEntry(description, skill, build or (lambda values, _: skill(**values)))

    def entry(self, name: str) -> SkillEntry:
        """The whole entry of a skill, or UnknownSkill naming the known ones."""
        try:
            return self._skills[name]
        except KeyError:
            raise UnknownSkill(name, list(self._skills)) from None

    def entries(self) -> list[SkillEntry]:
        """Every registered skill, in registration order."""
        return list(self._skills.values())
