"""What every robot farm offers: start, find by name, stop, list with load; and its refusals.

A farm runs simulated robots' skill servers and knows nothing of users: who owns a robot, and its
controller token, are kept by the caller (the practice robots' table). A farm restarts a robot that dies,
with the same name and controller token, so its user's seat and token survive; its address may change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from middleware.errors import Refused


class FarmUnavailable(Refused):
    """The farm cannot be reached or did not start the robot (503); nothing was left half-started."""

    def __init__(self, message: str) -> None:
        super().__init__(503, "farm_unavailable", message)


class FarmFull(Refused):
    """The farm holds as many robots as its hosts can run (409); the message says how many and what to do."""

    def __init__(self, message: str) -> None:
        super().__init__(409, "farm_full", message)


@dataclass(frozen=True)
class RobotSpec:
    """A simulated robot to start: its name, scene and the controller token it obeys from the start.

    fast robots step their world as fast as the host allows instead of in real time (a plan's prediction, which
    nobody watches live); they are throwaway: never restarted, and they end with the process that asked for them.
    """

    name: str
    scene: str
    controller_token: str = ""
    fast: bool = False


@dataclass(frozen=True)
class FarmRobot:
    """A robot the farm runs: where it listens, on which host, and what it costs now.

    cpu_share is the share of one core used since the last look (None before a second look);
    restarted says whether the farm had to restart it after a failure.
    """

    name: str
    scene: str
    address: str
    host: str
    backend: str
    node: str = ""  # the farm's name for the machine it runs on (a Ray node id; hosts may share an address)
    restarted: bool = False
    cpu_share: float | None = None
    memory_mb: float | None = None


@dataclass(frozen=True)
class Capacity:
    """How many robots the farm can hold (measured from its hosts' cores and memory) and how many run."""

    robots: int
    running: int
    hosts: int

    @property
    def free(self) -> int:
        """Robots that may still start."""
        return max(0, self.robots - self.running)


class RobotFarm(Protocol):
    """Runs simulated robots' skill servers; every method may raise FarmUnavailable."""

    backend: str

    def start(self, spec: RobotSpec) -> FarmRobot:
        """Starts the robot and waits until it serves; FarmFull when full. One of that name that runs already is
        answered if it obeys the same controller token, and replaced otherwise."""

    def find(self, name: str) -> FarmRobot | None:
        """The running robot called name, from any process."""

    def stop(self, name: str) -> bool:
        """Stops the robot; False if it was not running."""

    def robots(self) -> list[FarmRobot]:
        """Every running robot, with its load."""

    def capacity(self) -> Capacity:
        """How many robots the farm holds and runs now."""

    def close(self) -> None:
        """Lets go of the farm (a process leaving); the local farm stops its children."""
