"""The controller token and the latest drive command: the only robot state gRPC threads write."""

from __future__ import annotations

import threading
from dataclasses import dataclass

from skill_server.errors import InvalidParameter, MissingControllerToken, NotController
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

    def __init__(self, spec: RobotSpec) -> None:
        self._linear, self._angular = velocity_parameters(spec)
        self._lock = threading.Lock()
        self._token = ""
        self._last_sequence: int | None = None
        self._target = DriveTarget(0, 0, 0.0, 0.0, from_command=False)

    @property
    def controller_token(self) -> str:
        """The token whose commands are obeyed ("" when nobody has control)."""
        with self._lock:
            return self._token

    def set_controller(self, token: str) -> None:
        """Names the controller; a new or empty token stops the base and resets the sequence."""
        if not isinstance(token, str):
            raise InvalidParameter("token", "token must be a string")
        with self._lock:
            if token == self._token:
                return
            self._token = token
            self._last_sequence = None
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
