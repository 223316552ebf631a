"""Parameter schemas that skills publish and the server validates commands against (used by sim/ and skills/)."""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from skill_server.errors import InvalidParameter


class ParameterType(enum.Enum):
    """The kind of value a parameter takes."""

    DOUBLE = "double"
    INT = "int"
    BOOL = "bool"
    ENUM = "enum"


@dataclass(frozen=True)
class ParameterSchema:
    """One parameter of a skill: what a panel shows and what the server accepts."""

    name: str
    type: ParameterType
    unit: str
    minimum: float
    maximum: float
    default: float
    help: str
    choices: tuple[str, ...] = ()

    def validate(self, value: object) -> float | int | bool | str:
        """Returns the value if it is acceptable, else raises InvalidParameter naming this field."""
        if self.type is ParameterType.BOOL:
            if isinstance(value, bool):
                return value
            raise InvalidParameter(self.name, f"{self.name} must be true or false")
        if self.type is ParameterType.ENUM:
            if isinstance(value, str) and value in self.choices:
                return value
            raise InvalidParameter(self.name, f"{self.name} must be one of: {', '.join(self.choices)}")
        if self.type is ParameterType.INT:
            if isinstance(value, int) and not isinstance(value, bool) and self.minimum <= value <= self.maximum:
                return value
            raise InvalidParameter(self.name, f"{self.name} must be an integer {self._range_text()}")
        if (
            isinstance(value, (int, float))
            and not isinstance(value, bool)
            and math.isfinite(value)
            and self.minimum <= value <= self.maximum
        ):
            return float(value)
        raise InvalidParameter(self.name, f"{self.name} must be a finite number {self._range_text()}")

    def default_value(self) -> float | int | bool | str:
        """The default in the parameter's own type (the schema's number field holds it as a double)."""
        if self.type is ParameterType.BOOL:
            return bool(self.default)
        if self.type is ParameterType.ENUM:
            return self.choices[int(self.default)]
        if self.type is ParameterType.INT:
            return int(self.default)
        return float(self.default)

    def _range_text(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"between {self.minimum:g} and {self.maximum:g}{unit}"


@dataclass(frozen=True)
class SkillDescription:
    """A skill's name, human title, help text and parameter schemas."""

    name: str
    title: str
    help: str
    parameters: tuple[ParameterSchema, ...] = field(default_factory=tuple)

    def parameter(self, name: str) -> ParameterSchema:
        """The schema of one parameter by name."""
        for schema in self.parameters:
            if schema.name == name:
                return schema
        raise KeyError(name)

    def validate(self, values: Mapping[str, object]) -> dict[str, float | int | bool | str]:
        """Validates every declared parameter (missing ones take their default); unknown names are refused."""
        known = {schema.name for schema in self.parameters}
        for name in values:
            if name not in known:
                raise InvalidParameter(name, f"{name} is not a parameter of {self.name}; known: {sorted(known)}")
        return {
            schema.name: schema.validate(values[schema.name] if schema.name in values else schema.default_value())
            for schema in self.parameters
        }
