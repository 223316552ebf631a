"""Skills: controllers ticked by the world loop, each publishing its parameter schema."""

from __future__ import annotations

from skill_server.skills.registry import SkillRegistry, default_registry
from skill_server.skills.schema import ParameterSchema, ParameterType, SkillDescription

__all__ = ["ParameterSchema", "ParameterType", "SkillDescription", "SkillRegistry", "default_registry"]
