"""Runs an exercise's Python against a simulated world stepped as fast as it computes (CPython, not Pyodide):
the same robot API file the browser runs (client_ui/static/pages/exercises/telelab.py), a backend that steps a
World of the real simulator instead of the page, and the ground truth sampled at the pose log's 5 Hz."""

from __future__ import annotations

import importlib.util
import random
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.world import World

API_FILE = Path(__file__).resolve().parents[3] / "client_ui" / "static" / "pages" / "exercises" / "telelab.py"
TOKEN = "exercise-test"
SAMPLE_S = 0.2  # the robot's pose log samples at 5 Hz


def load_api() -> ModuleType:
    """A fresh copy of the robot API module, importable as `telelab` by the student's code."""
    spec = importlib.util.spec_from_file_location("telelab", API_FILE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    previous = sys.modules.get("telelab")
    sys.modules["telelab"] = module  # dataclasses look their module up while the file runs
    try:
        spec.loader.exec_module(module)
    finally:
        if previous is not None:
            sys.modules["telelab"] = previous
    return module


class WorldBackend:
    """The API's backend over a world the test steps: time is the world's sim time since the run began.

    With telemetry_hz and latency_s the program reads the robot as the browser does: readings that change only at
    the telemetry stream's rate (10 Hz to the page) and are latency_s old when they arrive."""

    def __init__(self, world: World, time_limit_s: float, telemetry_hz: float = 0.0, latency_s: float = 0.0) -> None:
        self.world, self.time_limit_s = world, time_limit_s
        self.telemetry_period_s, self.latency_s = (1.0 / telemetry_hz if telemetry_hz else 0.0), latency_s
        self._heard: list[tuple[float, dict[str, Any]]] = []  # (sim time, reading) of the telemetry sent so far
        self.sequence, self.trace, self.reports = 0, [], []
        self.last_sent = (0.0, 0.0)
        self._t0 = world.snapshot.sim_time_s
        self._next_sample = 0.0
        self._outgoing: list[tuple[float, dict[str, Any]]] = []
        self._sample()

    def now(self) -> float:
        return self.world.snapshot.sim_time_s - self._t0

    def wait_until(self, t_s: float) -> bool:
        while self.now() < t_s - 1e-9:
            self.world.step_for(self.world.tick_dt_s)
            self._sample()
            if self.telemetry_period_s or self.latency_s:
                self._hear()
        return True

    def _sample(self) -> None:
        snapshot = self.world.snapshot
        t = snapshot.sim_time_s - self._t0
        if t + 1e-9 >= self._next_sample:
            self._next_sample += SAMPLE_S
            g, o = snapshot.ground_truth, snapshot.odometry.pose
            self.trace.append([round(t, 3), g.x_m, g.y_m, g.theta_rad, o.x_m, o.y_m, o.theta_rad])

    def read(self) -> dict[str, Any]:
        if not self.telemetry_period_s and not self.latency_s:
            return self._reading()
        return self._heard[-1][1] if self._heard else self._reading()

    def _hear(self) -> None:
        """Each world tick: a telemetry message leaves on the stream's grid and arrives latency_s later."""
        now = self.now()
        if not self._outgoing or now - self._outgoing[-1][0] >= self.telemetry_period_s - 1e-9:
            self._outgoing.append((now, self._reading()))
        while self._outgoing and self._outgoing[0][0] + self.latency_s <= now + 1e-9:
            self._heard.append(self._outgoing.pop(0))
        del self._heard[:-1]

    def _reading(self) -> dict[str, Any]:
        s = self.world.snapshot
        spec = LaserSpec()  # the world's default scanner
        angle_min, increment = spec.angle_min_rad, spec.angle_increment_rad
        return {"odometry": {"pose": {"x_m": s.odometry.pose.x_m, "y_m": s.odometry.pose.y_m,
                                      "theta_rad": s.odometry.pose.theta_rad},
                             "linear_mps": s.commanded_linear_mps, "angular_radps": s.commanded_angular_radps},
                "sonar": {"ranges_m": list(s.sonar_ranges_m)},
                "laser": {"angle_min_rad": angle_min, "angle_increment_rad": increment,
                          "ranges_m": list(s.laser_ranges_m)},
                "battery": {"charge": s.battery.charge},
                "line": {"values": list(s.line_readings)}}

    def send(self, linear_mps: float, angular_radps: float) -> None:
        self.last_sent = (linear_mps, angular_radps)
        self.sequence += 1
        self.world.drive(TOKEN, self.sequence, linear_mps, angular_radps)

    def skill(self, name: str, parameters: dict[str, Any], wait: bool = True) -> str:
        raise NotImplementedError("skills need the skill server; the reference solutions drive the wheels")

    def report(self, x_m: float, y_m: float, t_s: float) -> None:
        self.reports.append({"x_m": x_m, "y_m": y_m, "t_s": t_s})

    def limits(self) -> tuple[float, float, float]:
        limits = self.world.limits
        return limits.max_linear_mps, limits.max_angular_radps, self.time_limit_s


def random_start(region: dict[str, list[float]], seed: int) -> list[float]:
    """A start drawn from the exercise's hidden region, as the server draws it."""
    draw = random.Random(seed)
    return [draw.uniform(*region["x_m"]), draw.uniform(*region["y_m"]), draw.uniform(*region["theta_rad"])]


def run_code(code: str, scene: str, start: list[float], time_limit_s: float, seed: int, telemetry_hz: float = 0.0,
             latency_s: float = 0.0) -> WorldBackend:
    """Runs code as the student's program from start until it ends or its time is up; the backend holds the trace
    (telemetry_hz and latency_s: the readings as the browser gets them, WorldBackend)."""
    with World(scene, realtime=False, seed=seed) as world:
        world.set_controller(TOKEN)
        world.set_pose(Pose2D(*start))
        backend = WorldBackend(world, time_limit_s, telemetry_hz, latency_s)
        run_program(code, backend)
        return backend


def run_program(code: str, backend: Any) -> None:
    """Runs code as the student's program, `from telelab import robot` talking to backend."""
    api = load_api()
    api.attach(backend)
    previous = sys.modules.get("telelab")
    sys.modules["telelab"] = api
    try:
        exec(compile(code, "<exercise>", "exec"), {"__name__": "__main__"})  # noqa: S102 - the test's own code
    finally:
        if previous is None:
            sys.modules.pop("telelab", None)
        else:
            sys.modules["telelab"] = previous
