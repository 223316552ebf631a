"""The controller token, the latest drive command and the motion limits: the only robot state gRPC threads write."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, replace

from skill_server.errors import BatteryEmpty, InvalidParameter, MissingControllerToken, NotController
from skill_server.schema import ParameterSchema, ParameterType
from skill_server.sim.robot_model import RobotSpec


def velocity_parameters(spec: RobotSpec) -> tuple[ParameterSchema, ParameterSchema]:
    """What a velocity command may ask of the base: Drive commands and the direct_control skill share it."""
    linear_mps, angular_radps = spec.max_linear_mps, spec.max_angular_radps
    return (
        ParameterSchema("linear_mps", ParameterType.DOUBLE, "m/s", -linear_mps, linear_mps, 0.0,
                        "Forward speed; negative drives backwards."),
        ParameterSchema("angular_radps", ParameterType.DOUBLE, "rad/s", -angular_radps, angular_radps, 0.0,
                        "Turn rate; positive turns left (counter-clockwise)."),
    )


# The deadman (watchdog) timeout a controller may choose: below 0.2 s one late packet on a phone's link stops the
# base; above 5 s a lost browser leaves the robot driving blind for too long.
MIN_WATCHDOG_S, MAX_WATCHDOG_S = 0.2, 5.0
BATTERY_EMPTY_MESSAGE = ("the battery is empty: the base will not move until the robot is recharged at its dock "
                         "(return it to the dock)")


@dataclass(frozen=True)
class MotionLimits:
    """The velocity ceilings every motion source obeys and the deadman timeout of direct drive commands."""

    max_linear_mps: float
    max_angular_radps: float
    watchdog_s: float
    robot_max_linear_mps: float  # the robot's own: the most a ceiling may be set to
    robot_max_angular_radps: float

    min_watchdog_s = MIN_WATCHDOG_S
    max_watchdog_s = MAX_WATCHDOG_S

    def clamp(self, linear_mps: float, angular_radps: float) -> tuple[float, float]:
        """The velocities within the ceilings (the sign kept)."""
        return (max(-self.max_linear_mps, min(self.max_linear_mps, linear_mps)),
                max(-self.max_angular_radps, min(self.max_angular_radps, angular_radps)))


def _limit_value(field: str, value: object, low: float, high: float, unit: str, low_open: bool) -> float | None:
    """A new limit value, None for 0 (keep the current one); InvalidParameter naming field otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InvalidParameter(field, f"{field} must be a finite number of {unit} (0 keeps the current value)")
    if value == 0:
        return None
    if (value <= low if low_open else value < low) or value > high:
        bounds = f"above {low:g} and at most {high:g}" if low_open else f"between {low:g} and {high:g}"
        raise InvalidParameter(field, f"{field} must be {bounds} {unit} (0 keeps the current value); got {value:g}")
    return float(value)


@dataclass(frozen=True)
class DriveTarget:
    """What the base should do; version grows with every change so the loop can tell a new one."""

    version: int
    sequence: int
    linear_mps: float
    angular_radps: float
    from_command: bool  # False when the target is a stop caused by a controller change


@dataclass(frozen=True)
class DriveAck:
    """The answer to a drive command: the sequence in force and the velocities now commanded."""

    applied_sequence: int
    linear_mps: float
    angular_radps: float


class DriveGate:
    """Checks token, values and sequence of drive commands, and holds the latest accepted one.

    A latest-wins mailbox rather than a queue: the loop only ever needs the newest command, and a
    burst of commands must never build a backlog behind a slow tick.
    """

    def __init__(self, spec: RobotSpec, watchdog_s: float = 0.4) -> None:
        self._linear, self._angular = velocity_parameters(spec)
        self._lock = threading.Lock()
        self._token = ""
        self._last_sequence: int | None = None
        self._target = DriveTarget(0, 0, 0.0, 0.0, from_command=False)
        self._limits = MotionLimits(spec.max_linear_mps, spec.max_angular_radps, watchdog_s, spec.max_linear_mps,
                                    spec.max_angular_radps)
        self._initial_limits = self._limits
        self._battery_empty = False

    @property
    def limits(self) -> MotionLimits:
        """The limits in force (read by the loop every tick)."""
        return self._limits

    def set_limits(self, token: str, max_linear_mps: object, max_angular_radps: object,
                   watchdog_s: object) -> MotionLimits:
        """The controller's new limits (0 keeps a value); every value is checked before any changes."""
        if not token:
            raise MissingControllerToken("changing the limits needs the controller token")
        with self._lock:
            if token != self._token:
                raise NotController("this request's controller token is not the robot's current controller")
            old = self._limits
            linear = _limit_value("max_linear_mps", max_linear_mps, 0.0, old.robot_max_linear_mps, "m/s", True)
            angular = _limit_value("max_angular_radps", max_angular_radps, 0.0, old.robot_max_angular_radps,
                                   "rad/s", True)
            watchdog = _limit_value("watchdog_s", watchdog_s, MIN_WATCHDOG_S, MAX_WATCHDOG_S, "s", False)
            self._limits = replace(old, max_linear_mps=old.max_linear_mps if linear is None else linear,
                                   max_angular_radps=old.max_angular_radps if angular is None else angular,
                                   watchdog_s=old.watchdog_s if watchdog is None else watchdog)
            return self._limits

    def note_battery(self, empty: bool) -> None:
        """The loop says whether the battery is empty; while it is, only stops are accepted."""
        self._battery_empty = empty

    @property
    def controller_token(self) -> str:
        """The token whose commands are obeyed ("" when nobody has control)."""
        with self._lock:
            return self._token

    def set_controller(self, token: str) -> None:
        """Names the controller; a new or empty token stops the base, resets the sequence and the limits."""
        if not isinstance(token, str):
            raise InvalidParameter("token", "token must be a string")
        with self._lock:
            if token == self._token:
                return
            self._token = token
            self._last_sequence = None
            self._limits = self._initial_limits  # each controller starts from the robot's own settings
            self._target = DriveTarget(self._target.version + 1, 0, 0.0, 0.0, from_command=False)

    def submit(self, token: str, sequence: int, linear_mps: object, angular_radps: object) -> DriveAck:
        """Accepts the controller's valid command if newer than the last; older ones are ignored."""
        if not token:
            raise MissingControllerToken("a drive command needs the controller token")
        with self._lock:
            if token != self._token:
                raise NotController("this command's controller token is not the robot's current controller")
            if isinstance(sequence, bool) or not isinstance(sequence, int) or sequence < 0:
                raise InvalidParameter("sequence", "sequence must be a non-negative integer")
            linear, angular = float(self._linear.validate(linear_mps)), float(self._angular.validate(angular_radps))
            if self._battery_empty and (linear or angular):
                raise BatteryEmpty(BATTERY_EMPTY_MESSAGE)
            linear, angular = self._limits.clamp(linear, angular)
            if self._last_sequence is None or sequence > self._last_sequence:
                self._last_sequence = sequence
                self._target = DriveTarget(self._target.version + 1, sequence, linear, angular, from_command=True)
            target = self._target
        return DriveAck(target.sequence, target.linear_mps, target.angular_radps)

    def latest(self) -> DriveTarget:
        """The newest target (read by the world's loop every tick)."""
        with self._lock:
            return self._target

    def stopped_by_deadman(self, version: int) -> None:
        """Records that the loop stopped the base for target version, so later acks report zero velocities."""
        with self._lock:
            if self._target.version == version:
                t = self._target
                self._target = DriveTarget(t.version, t.sequence, 0.0, 0.0, t.from_command)
