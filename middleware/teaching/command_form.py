"""Declarative robot commands (a skill with parameters, a drive, a stop), checked against a skill schema.

Pure: no Flask, no gRPC. The same form is used by lesson cues and tour steps. A command is data; nothing
in it is ever run as code. Errors name the field ("parameters.goal_x_m", "drive.linear_mps").
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from middleware.errors import Refused

SKILL_NAME = re.compile(r"^[a-z][a-z0-9_]{0,63}$")
MAX_LINEAR_MPS = 0.5
MAX_ANGULAR_RADPS = 1.5
MAX_TEXT = 64
MIN_TONE_HZ, MAX_TONE_HZ = 100, 4000
MIN_SOUND_S, MAX_SOUND_S = 0.05, 5.0
MAX_CAPTION = 120

# name -> list of parameter schemas as middleware.robots.messages.parameter_schema_dict gives them
SkillSchemas = Mapping[str, Sequence[Mapping[str, object]]]


class CommandInvalid(Refused, ValueError):
    """A command that cannot be used (400 invalid_field); field names the offending part."""

    field: str

    def __init__(self, field: str, message: str) -> None:
        super().__init__(400, "invalid_field", message, field)


@dataclass(frozen=True)
class RobotCommand:
    """One checked command: kind is 'skill', 'drive', 'stop' or 'sound'."""

    kind: str
    skill: str = ""
    parameters: tuple[tuple[str, object], ...] = ()
    linear_mps: float = 0.0
    angular_radps: float = 0.0
    # A sound (lesson cues only): a tone the robot's speaker plays in the learner's browser, and its caption.
    frequency_hz: float = 0.0
    duration_s: float = 0.0
    caption: str = ""

    def motion(self) -> RobotCommand:
        """What the robot's base does: a sound is played by the page while the robot stands still."""
        return RobotCommand("stop") if self.kind == "sound" else self

    def to_dict(self) -> dict[str, object]:
        """The canonical JSON form."""
        if self.kind == "skill":
            return {"skill": self.skill, "parameters": dict(self.parameters)}
        if self.kind == "drive":
            return {"drive": {"linear_mps": self.linear_mps, "angular_radps": self.angular_radps}}
        if self.kind == "sound":
            return {"sound": {"frequency_hz": self.frequency_hz, "duration_s": self.duration_s,
                              "caption": self.caption}}
        return {"stop": True}


def _number(value: object, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CommandInvalid(field, f"{field} must be a number.")
    try:
        number = float(value)
    except OverflowError:  # an int from JSON too large for a float
        raise CommandInvalid(field, f"{field} must be a finite number.") from None
    if not math.isfinite(number):
        raise CommandInvalid(field, f"{field} must be a finite number.")
    return number


def check_parameter(name: str, value: object, schema: Mapping[str, object]) -> object:
    """value checked against one parameter schema (type, range, choices); CommandInvalid naming the field."""
    field = f"parameters.{name}"
    kind = schema.get("type")
    if kind == "bool":
        if not isinstance(value, bool):
            raise CommandInvalid(field, f"{name} must be true or false.")
        return value
    if kind == "enum":
        listed = schema.get("choices")
        choices = [str(c) for c in listed] if isinstance(listed, list | tuple) else []
        if not isinstance(value, str) or value not in choices:
            raise CommandInvalid(field, f"{name} must be one of {', '.join(choices)}.")
        return value
    if kind in {"double", "int"}:
        number = _number(value, field)
        if kind == "int" and not (isinstance(value, int) or number.is_integer()):
            raise CommandInvalid(field, f"{name} must be a whole number.")
        low, high = float(schema.get("minimum", -math.inf)), float(schema.get("maximum", math.inf))  # type: ignore[arg-type]
        if (low or high) and not low <= number <= high:
            raise CommandInvalid(field, f"{name} must be between {low:g} and {high:g}{_unit(schema)}.")
        return int(number) if kind == "int" else number
    if not isinstance(value, str) or len(value) > MAX_TEXT:
        raise CommandInvalid(field, f"{name} must be a word of at most {MAX_TEXT} characters.")
    return value


def _unit(schema: Mapping[str, object]) -> str:
    unit = schema.get("unit")
    return f" {unit}" if unit else ""


def parse_skill(skill: object, parameters: object, skills: SkillSchemas | None) -> RobotCommand:
    """A skill command; with skills given, the name and every parameter are checked against their schema."""
    if not isinstance(skill, str) or not SKILL_NAME.fullmatch(skill):
        raise CommandInvalid("skill", "skill must be a skill name such as go_to_goal.")
    if skills is not None and skill not in skills:
        raise CommandInvalid("skill", f"The robot has no skill {skill!r}; it has {', '.join(sorted(skills))}.")
    if parameters is None:
        parameters = {}
    if not isinstance(parameters, dict) or len(parameters) > 32:
        raise CommandInvalid("parameters", "parameters must be an object of at most 32 values.")
    schema = {str(p["name"]): p for p in skills[skill]} if skills is not None else None
    checked: list[tuple[str, object]] = []
    for name, value in parameters.items():
        if not isinstance(name, str) or not SKILL_NAME.fullmatch(name):
            raise CommandInvalid("parameters", f"{str(name)[:40]!r} is not a parameter name.")
        if schema is not None:
            if name not in schema:
                known = ", ".join(schema) or "none"
                raise CommandInvalid(f"parameters.{name}", f"{skill} has no parameter {name!r} (it has {known}).")
            checked.append((name, check_parameter(name, value, schema[name])))
        elif isinstance(value, bool | str | int | float):
            checked.append((name, _number(value, f"parameters.{name}") if isinstance(value, float) else value))
        else:
            raise CommandInvalid(f"parameters.{name}", f"{name} must be a number, true/false or a word.")
    return RobotCommand("skill", skill, tuple(checked))


def parse_sound(sound: object) -> RobotCommand:
    """A sound: {"frequency_hz", "duration_s", "caption"}; the caption is required, for those who cannot hear it."""
    if not isinstance(sound, dict) or set(sound) - {"frequency_hz", "duration_s", "caption"}:
        raise CommandInvalid("sound", "sound takes frequency_hz, duration_s and caption only.")
    frequency = _number(sound.get("frequency_hz", 880), "sound.frequency_hz")
    if not MIN_TONE_HZ <= frequency <= MAX_TONE_HZ:
        raise CommandInvalid("sound.frequency_hz", f"frequency_hz must be between {MIN_TONE_HZ} and {MAX_TONE_HZ} Hz.")
    duration = _number(sound.get("duration_s", 0.5), "sound.duration_s")
    if not MIN_SOUND_S <= duration <= MAX_SOUND_S:
        raise CommandInvalid("sound.duration_s", f"duration_s must be between {MIN_SOUND_S} and {MAX_SOUND_S} s.")
    caption = sound.get("caption")
    if not isinstance(caption, str) or not caption.strip() or len(caption.strip()) > MAX_CAPTION:
        raise CommandInvalid("sound.caption", f"A sound needs a caption of 1 to {MAX_CAPTION} characters, shown to "
                                              "those who cannot hear it (e.g. \"The robot beeps, high\").")
    return RobotCommand("sound", frequency_hz=frequency, duration_s=duration, caption=" ".join(caption.split()))


def parse_command(value: object, skills: SkillSchemas | None, sounds: bool = False) -> RobotCommand:
    """A checked command from its JSON form: {"skill", "parameters"}, {"drive": {...}} or {"stop": true}; with
    sounds (a lesson's cues), also {"sound": {...}}."""
    if not isinstance(value, dict):
        raise CommandInvalid("command", 'A command is a JSON object: {"skill": ...}, {"drive": ...} or {"stop": true}.')
    kinds = [k for k in ("skill", "drive", "stop", "sound") if k in value]
    if "sound" in kinds and not sounds:
        raise CommandInvalid("sound", "Only a lesson's cues play sounds.")
    if len(kinds) != 1:
        raise CommandInvalid("command", 'A command has exactly one of "skill", "drive", "stop" or "sound".')
    if kinds == ["sound"] and set(value) == {"sound"}:
        return parse_sound(value["sound"])
    extra = set(value) - {"skill", "parameters"} if kinds == ["skill"] else set(value) - set(kinds)
    if extra:
        raise CommandInvalid(sorted(extra)[0][:40], f"Unknown key {sorted(extra)[0][:40]!r} in the command.")
    if kinds == ["stop"]:
        if value["stop"] is not True:
            raise CommandInvalid("stop", 'stop must be true: {"stop": true}.')
        return RobotCommand("stop")
    if kinds == ["drive"]:
        drive = value["drive"]
        if not isinstance(drive, dict) or set(drive) - {"linear_mps", "angular_radps"}:
            raise CommandInvalid("drive", "drive takes linear_mps and angular_radps only.")
        linear = _number(drive.get("linear_mps", 0.0), "drive.linear_mps")
        angular = _number(drive.get("angular_radps", 0.0), "drive.angular_radps")
        if abs(linear) > MAX_LINEAR_MPS:
            raise CommandInvalid("drive.linear_mps", f"linear_mps must be between -{MAX_LINEAR_MPS} and "
                                                     f"{MAX_LINEAR_MPS} m/s.")
        if abs(angular) > MAX_ANGULAR_RADPS:
            raise CommandInvalid("drive.angular_radps", f"angular_radps must be between -{MAX_ANGULAR_RADPS} and "
                                                        f"{MAX_ANGULAR_RADPS} rad/s.")
        return RobotCommand("drive", linear_mps=linear, angular_radps=angular)
    return parse_skill(value["skill"], value.get("parameters"), skills)
