"""Domain errors of the robot core; the gRPC adapter maps each to a status code."""

from __future__ import annotations


class RobotError(Exception):
    """Base class of every error the robot core raises on purpose."""


class InvalidParameter(RobotError):
    """A command's parameter is missing, not finite, of the wrong type or out of range."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field
        self.message = message


class MissingControllerToken(RobotError):
    """A command came without a controller token."""


class NotController(RobotError):
    """A command's token is not the robot's current controller."""


class UnknownScene(RobotError, ValueError):
    """A scene name that no scene was registered under."""

    def __init__(self, name: str, known: list[str]) -> None:
        super().__init__(f"unknown scene {name!r}; known scenes: {', '.join(sorted(known))}")
        self.name = name
        self.known = sorted(known)


class WorldStopped(RobotError):
    """The world's loop is not running, so it cannot take the command."""
