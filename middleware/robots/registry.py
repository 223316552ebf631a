"""The robots this middleware process knows, one RobotLink each."""

from __future__ import annotations

from flask import Flask, current_app

from middleware.config import RobotAddress
from middleware.robots.link import RobotLink

_EXTENSION_KEY = "telelab.robots"


class RobotRegistry:
    """Links to every configured robot, created once per process."""

    def __init__(self, robots: tuple[RobotAddress, ...], rpc_timeout_s: float) -> None:
        self.addresses = {robot.name: robot for robot in robots}
        self._links = {robot.name: RobotLink(robot.name, robot.address, rpc_timeout_s) for robot in robots}

    def get(self, name: str) -> RobotLink | None:
        """The link to the robot called name, if there is one."""
        return self._links.get(name)

    def names(self) -> list[str]:
        """Every robot's name, in configuration order."""
        return list(self._links)

    def close(self) -> None:
        """Closes every link (application shutdown, tests)."""
        for link in self._links.values():
            link.close()


def init_app(app: Flask) -> None:
    """Creates the registry for app from its ROBOTS setting."""
    app.extensions[_EXTENSION_KEY] = RobotRegistry(app.config["ROBOTS"], app.config["ROBOT_RPC_TIMEOUT_S"])


def robot_registry(app: Flask | None = None) -> RobotRegistry:
    """The registry of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
