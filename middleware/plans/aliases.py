"""The text form's short names for skills: go_to, turn_to and follow_wall, each the real skill of the catalogue
(skill_server/skills/catalog.py) with its first parameters written by position."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Alias:
    """A short command for a skill: positional are its parameters written without name, the first required of them
    needed; keywords are short names for others (besides the rule that speed stands for speed_mps)."""

    skill: str
    positional: tuple[str, ...]
    required: int
    keywords: Mapping[str, str] = field(default_factory=dict)
    example: str = ""


ALIASES: dict[str, Alias] = {
    "go_to": Alias("go_to_goal", ("goal_x_m", "goal_y_m"), 2, {"tolerance": "max_error_m"}, "go_to 1.2 0.5"),
    "turn_to": Alias("orientation_control", ("heading_rad",), 1,
                     {"max_turn_rate": "max_angular_radps"}, "turn_to 90deg"),
    "follow_wall": Alias("wall_following", ("side", "distance_m"), 1, {}, "follow_wall left 0.4 for 20s"),
}
ALIAS_OF_SKILL = {alias.skill: name for name, alias in ALIASES.items()}

# a key without its unit suffix names the parameter: speed=0.3 is speed_mps, timeout=60 is timeout_s
UNIT_SUFFIXES = ("m", "s", "mps", "rad", "radps")


def parameter_for_key(key: str, parameters: Mapping[str, object], alias: Alias | None) -> str:
    """The parameter a key=value names: itself, an alias's short name, or the one parameter that is key plus a
    unit suffix; otherwise the key unchanged (the check then says it is unknown)."""
    if key in parameters:
        return key
    if alias is not None and key in alias.keywords:
        return alias.keywords[key]
    matches = [f"{key}_{suffix}" for suffix in UNIT_SUFFIXES if f"{key}_{suffix}" in parameters]
    return matches[0] if len(matches) == 1 else key
