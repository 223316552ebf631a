"""Declarative robot commands (a skill with parameters, a drive, a stop), checked against a skill schema.

Pure: no Flask, no gRPC. The same form is used by lesson cues and tour steps. A command is data; nothing
in it is ever run as code. Errors name the field ("parameters.goal_x_m", "drive.linear_mps").
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import Refused, written_number

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
        raise CommandInvalid(field, gettext("%(field)s must be a number.", field=field))
    try:
        number = float(value)
    except OverflowError:  # an int from JSON too large for a float
        raise CommandInvalid(field, gettext("%(field)s must be a finite number.", field=field)) from None
    if not math.isfinite(number):
        raise CommandInvalid(field, gettext("%(field)s must be a finite number.", field=field))
    return number


def check_parameter(name: str, value: object, schema: Mapping[str, object]) -> object:
    """value checked against one parameter schema (type, range, choices); CommandInvalid naming the field."""
    field = f"parameters.{name}"
    kind = schema.get("type")
    if kind == "bool":
        if not isinstance(value, bool):
            raise CommandInvalid(field, gettext("%(field)s must be true or false.", field=name))
        return value
    if kind == "enum":
        listed = schema.get("choices")
        choices = [str(c) for c in listed] if isinstance(listed, list | tuple) else []
        if not isinstance(value, str) or value not in choices:
            raise CommandInvalid(field, gettext("%(name)s must be one of %(choices)s.", name=name,
                                                choices=", ".join(choices)))
        return value
    if kind in {"double", "int"}:
        number = _number(value, field)
        if kind == "int" and not (isinstance(value, int) or number.is_integer()):
            raise CommandInvalid(field, gettext("%(name)s must be a whole number.", name=name))
        low, high = float(schema.get("minimum", -math.inf)), float(schema.get("maximum", math.inf))  # type: ignore[arg-type]
        if (low or high) and not low <= number <= high:
            raise CommandInvalid(field, gettext("%(name)s must be between %(low)s and %(high)s%(unit)s.", name=name,
                                                low=written_number(low, "g"), high=written_number(high, "g"),
                                                unit=_unit(schema)))
        return int(number) if kind == "int" else number
    if not isinstance(value, str) or len(value) > MAX_TEXT:
        raise CommandInvalid(field, gettext("%(name)s must be a word of at most %(max_text)s characters.", name=name,
                                        max_text=MAX_TEXT))
    return value


def _unit(schema: Mapping[str, object]) -> str:
    unit = schema.get("unit")
    return f" {unit}" if unit else ""


def parse_skill(skill: object, parameters: object, skills: SkillSchemas | None) -> RobotCommand:
    """A skill command; with skills given, the name and every parameter are checked against their schema."""
    if not isinstance(skill, str) or not SKILL_NAME.fullmatch(skill):
        raise CommandInvalid("skill", gettext("skill must be a skill name such as go_to_goal."))
    if skills is not None and skill not in skills:
        raise CommandInvalid("skill", gettext("The robot has no skill %(skill)s; it has %(skills)s.", skill=repr(skill),
                                              skills=", ".join(sorted(skills))))
    if parameters is None:
        parameters = {}
    if not isinstance(parameters, dict) or len(parameters) > 32:
        raise CommandInvalid("parameters", gettext("parameters must be an object of at most %(max_parameters)s values.",
                                                   max_parameters=32))
    schema = {str(p["name"]): p for p in skills[skill]} if skills is not None else None
    checked: list[tuple[str, object]] = []
    for name, value in parameters.items():
        if not isinstance(name, str) or not SKILL_NAME.fullmatch(name):
            raise CommandInvalid("parameters", gettext("%(value)s is not a parameter name.",
                                                       value=repr(str(name)[:40])))
        if schema is not None:
            if name not in schema:
                known = ", ".join(schema) or gettext("none")
                raise CommandInvalid(f"parameters.{name}", gettext("%(skill)s has no parameter %(name)s (it has "
                                                                   "%(known)s).", skill=skill, name=repr(name),
                                                                   known=known))
            checked.append((name, check_parameter(name, value, schema[name])))
        elif isinstance(value, bool | str | int | float):
            checked.append((name, _number(value, f"parameters.{name}") if isinstance(value, float) else value))
        else:
            raise CommandInvalid(f"parameters.{name}", gettext("%(name)s must be a number, true/false or a word.",
                                                               name=name))
    return RobotCommand("skill", skill, tuple(checked))


def parse_sound(sound: object) -> RobotCommand:
    """A sound: {"frequency_hz", "duration_s", "caption"}; the caption is required, for those who cannot hear it."""
    if not isinstance(sound, dict) or set(sound) - {"frequency_hz", "duration_s", "caption"}:
        raise CommandInvalid("sound", gettext("sound takes frequency_hz, duration_s and caption only."))
    frequency = _number(sound.get("frequency_hz", 880), "sound.frequency_hz")
    if not MIN_TONE_HZ <= frequency <= MAX_TONE_HZ:
        raise CommandInvalid("sound.frequency_hz", gettext("frequency_hz must be between %(low)s and %(high)s Hz.",
                                                           low=MIN_TONE_HZ, high=MAX_TONE_HZ))
    duration = _number(sound.get("duration_s", 0.5), "sound.duration_s")
    if not MIN_SOUND_S <= duration <= MAX_SOUND_S:
        raise CommandInvalid("sound.duration_s", gettext("duration_s must be between %(low)s and %(high)s s.",
                                                         low=written_number(MIN_SOUND_S),
                                                         high=written_number(MAX_SOUND_S)))
    caption = sound.get("caption")
    if not isinstance(caption, str) or not caption.strip() or len(caption.strip()) > MAX_CAPTION:
        raise CommandInvalid("sound.caption", gettext("A sound needs a caption of 1 to %(max_caption)s characters, "
                                                      "shown to those who cannot hear it (e.g. \"The robot beeps, "
                                                      "high\").", max_caption=MAX_CAPTION))
    return RobotCommand("sound", frequency_hz=frequency, duration_s=duration, caption=" ".join(caption.split()))


def parse_command(value: object, skills: SkillSchemas | None, sounds: bool = False) -> RobotCommand:
    """A checked command from its JSON form: {"skill", "parameters"}, {"drive": {...}} or {"stop": true}; with
    sounds (a lesson's cues), also {"sound": {...}}."""
    if not isinstance(value, dict):
        raise CommandInvalid("command", gettext('A command is a JSON object: {"skill": ...}, {"drive": ...} or '
                                                 '{"stop": true}.'))
    kinds = [k for k in ("skill", "drive", "stop", "sound") if k in value]
    if "sound" in kinds and not sounds:
        raise CommandInvalid("sound", gettext("Only a lesson's cues play sounds."))
    if len(kinds) != 1:
        raise CommandInvalid("command", gettext('A command has exactly one of "skill", "drive", "stop" or "sound".'))
    if kinds == ["sound"] and set(value) == {"sound"}:
        return parse_sound(value["sound"])
    extra = set(value) - {"skill", "parameters"} if kinds == ["skill"] else set(value) - set(kinds)
    if extra:
        raise CommandInvalid(sorted(extra)[0][:40], gettext("Unknown key %(key)s in the command.",
                                                            key=repr(sorted(extra)[0][:40])))
    if kinds == ["stop"]:
        if value["stop"] is not True:
            raise CommandInvalid("stop", gettext('stop must be true: {"stop": true}.'))
        return RobotCommand("stop")
    if kinds == ["drive"]:
        drive = value["drive"]
        if not isinstance(drive, dict) or set(drive) - {"linear_mps", "angular_radps"}:
            raise CommandInvalid("drive", gettext("drive takes linear_mps and angular_radps only."))
        linear = _number(drive.get("linear_mps", 0.0), "drive.linear_mps")
        angular = _number(drive.get("angular_radps", 0.0), "drive.angular_radps")
        if abs(linear) > MAX_LINEAR_MPS:
            raise CommandInvalid("drive.linear_mps", gettext("linear_mps must be between -%(high)s and %(high)s m/s.",
                                                             high=written_number(MAX_LINEAR_MPS)))
        if abs(angular) > MAX_ANGULAR_RADPS:
            raise CommandInvalid("drive.angular_radps", gettext("angular_radps must be between -%(high)s and %(high)s "
                                                                "rad/s.", high=written_number(MAX_ANGULAR_RADPS)))
        return RobotCommand("drive", linear_mps=linear, angular_radps=angular)
    return parse_skill(value["skill"], value.get("parameters"), skills)
