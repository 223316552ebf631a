"""The skill schemas of the real catalogue (skill_server/skills/catalog.py), converted exactly as they travel:
SkillDescription -> robot_pb2 (skill_server.service.convert) -> dict (middleware.robots.messages)."""

from __future__ import annotations

from functools import cache

from middleware.robots.messages import parameter_schema_dict
from middleware.teaching.command_form import SkillSchemas
from skill_server.service.convert import skill_to_proto
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.catalog import default_registry


@cache
def catalogue_schemas() -> SkillSchemas:
    """name -> parameter schemas of every skill a default robot offers."""
    return {entry.description.name: [parameter_schema_dict(p) for p in skill_to_proto(entry).parameters]
            for entry in default_registry(RobotSpec()).entries()}


def motor_schemas() -> SkillSchemas:
    """Only the skills that drive the base (the ones a plan may run)."""
    motor = {entry.description.name for entry in default_registry(RobotSpec()).entries() if entry.motor}
    return {name: schema for name, schema in catalogue_schemas().items() if name in motor}
