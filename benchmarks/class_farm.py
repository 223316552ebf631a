"""The class-day benchmark's farm: the stand-in robots served as `telelab up`'s local farm owner serves robots, so that
a class session starts its students' practice robots through the product's own farm protocol."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import grpc

from benchmarks.standin_robots import StandInFleet
from benchmarks.web_tier import ROOT
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

# The local farm owner's settings (middleware/farm/owner.py ADDRESS_VARIABLE, KEY_VARIABLE), named here because this
# process does not import the middleware (seconds of a busy host); the farm's own process reads them by those names.
FARM_ADDRESS_VARIABLE, FARM_KEY_VARIABLE = "TELELAB_LOCAL_FARM", "TELELAB_LOCAL_FARM_KEY"


class StandInFarm:
    """The class's farm: a process of its own that speaks the protocol of `telelab up`'s local farm owner
    (middleware/farm/owner.py), which the web workers reach as their farm, so a class session starts its students'
    robots as in the product. A start hands the stand-in of the robot's name its owner's token (SetController), as a
    farm starts a robot that obeys it; a stop takes the token back."""

    def __init__(self, fleet: StandInFleet) -> None:
        self._folder = Path(tempfile.mkdtemp(prefix="telelab-farm-"))  # mode 0700; a Unix socket's path is short
        self.environment = {FARM_ADDRESS_VARIABLE: str(self._folder / "farm.sock"),
                            FARM_KEY_VARIABLE: os.urandom(32).hex()}
        # Started now: its imports of the middleware overlap the database's set-up and the workers' start.
        self.process = subprocess.Popen([sys.executable, "-c", "import benchmarks.class_farm as c; c.serve_farm()"],
                                        cwd=ROOT, env={**os.environ, **self.environment,
                                                       "TELELAB_ROBOTS": fleet.robots_setting},
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def wait_until_serving(self) -> None:
        assert self.process.stdout is not None
        if self.process.stdout.readline().strip() != "serving":
            raise RuntimeError(f"the stand-in farm did not start (exit code {self.process.wait()})")

    def stop(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()  # it serves until its stdin closes
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)
        shutil.rmtree(self._folder, ignore_errors=True)


def serve_farm() -> None:
    """The stand-in farm's process (StandInFarm): the robots of TELELAB_ROBOTS, served until stdin closes."""
    from multiprocessing.managers import BaseManager

    from middleware.config import parse_robots
    from middleware.farm.base import Capacity, FarmRobot, RobotSpec
    from middleware.farm.owner import ADDRESS_VARIABLE, FARM_METHODS, KEY_VARIABLE

    addresses = {robot.name: robot.address for robot in parse_robots(os.environ["TELELAB_ROBOTS"])}
    started: dict[str, FarmRobot] = {}

    def hand_over(address: str, token: str) -> None:
        with grpc.insecure_channel(address) as channel:
            robot_pb2_grpc.RobotStub(channel).SetController(robot_pb2.SetControllerRequest(token=token), timeout=10)

    class Farm:
        backend = "local"

        def start(self, spec: RobotSpec) -> FarmRobot:
            hand_over(addresses[spec.name], spec.controller_token)
            started[spec.name] = FarmRobot(spec.name, spec.scene, addresses[spec.name], "localhost", self.backend)
            return started[spec.name]

        def find(self, name: str) -> FarmRobot | None:
            return started.get(name)

        def stop(self, name: str) -> bool:
            robot = started.pop(name, None)
            if robot is not None:
                hand_over(robot.address, "")
            return robot is not None

        def robots(self) -> list[FarmRobot]:
            return list(started.values())

        def capacity(self) -> Capacity:
            return Capacity(len(addresses), len(started), 1)

    class Owner(BaseManager):
        pass

    farm = Farm()
    Owner.register("farm", callable=lambda: farm, exposed=FARM_METHODS)
    server = Owner(address=os.environ[ADDRESS_VARIABLE], authkey=bytes.fromhex(os.environ[KEY_VARIABLE])).get_server()
    threading.Thread(target=lambda: (sys.stdin.read(), os._exit(0)), daemon=True).start()
    print("serving", flush=True)
    server.serve_forever()
