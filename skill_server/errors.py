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


class UnknownSkill(RobotError):
    """A skill name that the robot does not offer."""

    def __init__(self, name: str, known: list[str]) -> None:
        super().__init__(f"unknown skill {name!r}; known skills: {', '.join(known)}")
        self.name = name


class UnknownGoal(RobotError):
    """A goal id that was never issued or whose record has been forgotten."""


class ResourceBusy(RobotError):
    """The resource a skill needs (the wheels, or a perceptive skill's slot) is held by another goal."""

    def __init__(self, message: str, holder_goal_id: str) -> None:
        super().__init__(message)
        self.holder_goal_id = holder_goal_id


class NoMap(RobotError):
    """Localization was asked for before any environment model exists."""


class NoTrack(RobotError):
    """A track's run or events were asked for in a scene without a track."""


class BatteryEmpty(RobotError):
    """The battery is empty: the base refuses to move until the robot is recharged at its dock."""


class NotRestartable(RobotError):
    """The robot runs inside another program (a test, a notebook): that program restarts it, not a request."""
