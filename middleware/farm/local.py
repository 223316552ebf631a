"""The local farm: each robot a child process of this process, as many as this host's capacity.

The embedded default for `make run`. Its robots are children of one process: the web process itself, or under
`telelab up --workers N` the farm owner process that every worker of the host asks (farm/owner.py). A lab
with several web hosts uses the Ray farm.
"""

from __future__ import annotations

import threading

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.farm.base import Capacity, FarmFull, FarmRobot, FarmUnavailable, RobotSpec
from middleware.farm.costs import available_memory_mb, host_cores, robot_cpu_share, robots_per_host
from middleware.farm.load import CpuMeter, resident_mb
from middleware.robots.processes import SkillServerProcess, SkillServerStartError

HOST = "localhost"


class LocalProcessFarm:
    """Robots as child processes, restarted when they die; refuses beyond the capacity measured at start."""

    backend = "local"

    def __init__(self, capacity: int | None = None, cpu_share: float | None = None) -> None:
        share = robot_cpu_share() if cpu_share is None else cpu_share
        self._capacity = robots_per_host(host_cores(), available_memory_mb(), cpu_share=share) \
            if capacity is None else capacity
        self._processes: dict[str, SkillServerProcess] = {}
        self._starting: set[str] = set()
        self._lock = threading.Lock()
        self._meter = CpuMeter()
        self._closed = False

    def start(self, spec: RobotSpec) -> FarmRobot:
        with self._lock:
            if self._closed:
                raise FarmUnavailable(gettext("The lab is shutting down; no robot starts now."))
            running = self._processes.get(spec.name)
            if running is not None and running.controller_token == spec.controller_token:
                return self._describe(running)
            if running is not None:  # its owner lost track of it (its record was removed): a fresh one replaces it
                del self._processes[spec.name]
            if spec.name in self._starting:
                raise FarmUnavailable(gettext("%(robot)s is starting already; wait a few seconds.", robot=spec.name))
            if len(self._processes) + len(self._starting) >= self._capacity:
                raise FarmFull(gettext("This host runs as many simulated robots as it can (%(capacity)s). Try again "
                                       "when a robot is stopped, or add a host to the lab's Ray farm.",
                                       capacity=self._capacity))
            self._starting.add(spec.name)
        if running is not None:
            running.stop()
        # Its robots end with this process (the web process, or the farm owner of farm/owner.py): nothing
        # else can reach them, and a robot left behind would hold a core until the host restarts.
        process = SkillServerProcess(spec.name, spec.scene, echo=False, controller_token=spec.controller_token,
                                     exit_with_parent=True, fast=spec.fast, restart=not spec.fast)
        try:
            process.serve()
        except SkillServerStartError as error:
            process.stop()
            raise FarmUnavailable(gettext("%(robot)s did not start: %(error)s", robot=spec.name, error=error)) from None
        finally:
            with self._lock:
                self._starting.discard(spec.name)
        with self._lock:
            closed = self._closed
            if not closed:
                self._processes[spec.name] = process
        if closed:  # the farm closed while this robot started: nobody would ever stop it
            process.stop()
            raise FarmUnavailable(gettext("The lab is shutting down; no robot starts now."))
        return self._describe(process)

    def find(self, name: str) -> FarmRobot | None:
        process = self._processes.get(name)
        return None if process is None else self._describe(process)

    def stop(self, name: str) -> bool:
        with self._lock:
            process = self._processes.pop(name, None)
        if process is None:
            return False
        process.stop()
        return True

    def robots(self) -> list[FarmRobot]:
        return [self._describe(process) for process in list(self._processes.values())]

    def capacity(self) -> Capacity:
        with self._lock:
            running = len(self._processes) + len(self._starting)
        return Capacity(self._capacity, running, hosts=1)

    def close(self) -> None:
        with self._lock:
            self._closed = True
        for name in list(self._processes):
            self.stop(name)

    def _describe(self, process: SkillServerProcess) -> FarmRobot:
        pid = process.process.pid if process.process is not None else None
        return FarmRobot(process.name, process.scene, process.address, HOST, self.backend, node=HOST,
                         restarted=process.restarts > 0,
                         cpu_share=None if pid is None else self._meter.share(pid),
                         memory_mb=None if pid is None else resident_mb(pid))
