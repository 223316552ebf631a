"""The robot API of Telelab's exercises: `from telelab import robot`.

The same file runs in the student's browser (Pyodide, in a Web Worker; the backend is the page) and in the
tests under CPython (the backend steps a simulated world). Nothing here decides a grade: the server grades the
run from the robot's own ground truth.

The loop runs at RATE_HZ (20 Hz): `while robot.tick():` waits for the next period on a fixed grid, reads the
sensors once, and sends the wheel command set since (the robot's deadman stops it when ticks stop coming). tick()
answers False once the exercise's time is up or Stop was pressed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

RATE_HZ = 20
PERIOD_S = 1.0 / RATE_HZ
CONTACT_M = 0.05  # the virtual bumper: an obstacle this close to the body, in front or on either side
BODY_RADIUS_M = 0.2
LINE_AHEAD_M = 0.16  # the line sensor's cells look at the floor this far ahead of the robot's centre,
LINE_OFFSETS_M = (0.045, 0.0225, 0.0, -0.0225, -0.045)  # at these offsets, left (+) to right


class Backend(Protocol):
    """Where the API's calls go: the browser page, or a simulated world in the tests."""

    def now(self) -> float: ...  # seconds since the run started
    def wait_until(self, t_s: float) -> bool: ...  # False when Stop was asked meanwhile
    def read(self) -> dict[str, Any]: ...  # the latest telemetry, as the page receives it
    def send(self, linear_mps: float, angular_radps: float) -> None: ...
    def skill(self, name: str, parameters: dict[str, Any], wait: bool = True) -> str: ...  # the final status
    def report(self, x_m: float, y_m: float, t_s: float) -> None: ...
    def limits(self) -> tuple[float, float, float]: ...  # max linear, max angular, time limit [s]


@dataclass(frozen=True)
class Pose:
    """Where odometry says the robot is: x_m, y_m, theta_rad, and its speeds."""

    x_m: float
    y_m: float
    theta_rad: float
    linear_mps: float = 0.0
    angular_radps: float = 0.0


@dataclass(frozen=True)
class Located:
    """The lab's localization estimate: x_m, y_m, theta_rad in the lab's frame, converged, and its spread std_m."""

    x_m: float
    y_m: float
    theta_rad: float
    converged: bool
    std_m: float


@dataclass(frozen=True)
class Scan:
    """A laser scan: ranges_m[i] is at angle angle_min_rad + i * increment_rad (0 straight ahead, left positive)."""

    angle_min_rad: float
    increment_rad: float
    ranges_m: tuple[float, ...]

    def angle(self, i: int) -> float:
        """The angle of beam i [rad]."""
        return self.angle_min_rad + i * self.increment_rad

    def nearest(self, from_rad: float, to_rad: float) -> float:
        """The shortest range between two angles [m] (inf when no beam falls there)."""
        chosen = [r for i, r in enumerate(self.ranges_m) if from_rad <= self.angle(i) <= to_rad]
        return min(chosen, default=math.inf)


class Robot:
    """The student's robot. Readings are those of the last tick; commands go out at the next tick."""

    def __init__(self, backend: Backend) -> None:
        self._backend = backend
        self._next_s = 0.0
        self._reading: dict[str, Any] = {}
        self._command = (0.0, 0.0)
        self._running = True
        self.max_linear_mps, self.max_angular_radps, self.time_limit_s = backend.limits()

    # ---- the loop ----
    def tick(self) -> bool:
        """Waits for the next period (RATE_HZ), sends the command, reads the sensors; False when the run is over."""
        if not self._running:
            return False
        now = self._backend.now()
        self._next_s = max(self._next_s + PERIOD_S, now)  # on a fixed grid; a late tick starts a new one
        if self._next_s >= self.time_limit_s or not self._backend.wait_until(self._next_s):
            self._finish()
            return False
        self._backend.send(*self._command)
        self._reading = self._backend.read()
        return True

    def sleep(self, seconds: float) -> bool:
        """Keeps ticking (the command in force goes on) for seconds; False when the run ended meanwhile."""
        until = self._backend.now() + float(seconds)
        while self._backend.now() < until - 1e-9:
            if not self.tick():
                return False
        return True

    def time(self) -> float:
        """Seconds since the run started."""
        return self._backend.now()

    # ---- commands ----
    def set_velocity(self, linear_mps: float, angular_radps: float) -> None:
        """The wheels' command from the next tick: forward speed [m/s] and turn rate [rad/s, left positive]."""
        linear, angular = float(linear_mps), float(angular_radps)
        if not (math.isfinite(linear) and math.isfinite(angular)):
            raise ValueError("set_velocity needs finite numbers")
        if abs(linear) > self.max_linear_mps + 1e-9:
            raise ValueError(f"linear_mps must be within ±{self.max_linear_mps:g} m/s; got {linear:g}")
        if abs(angular) > self.max_angular_radps + 1e-9:
            raise ValueError(f"angular_radps must be within ±{self.max_angular_radps:g} rad/s; got {angular:g}")
        self._command = (linear, angular)

    def stop(self) -> None:
        """Zero velocity from the next tick."""
        self._command = (0.0, 0.0)

    def run_skill(self, name: str, **parameters: Any) -> str:
        """Runs one of the robot's skills (go_to_goal, wall_following, ...) and waits for its end; its final status
        (SUCCEEDED, ABORTED, CANCELED)."""
        self._command = (0.0, 0.0)
        return self._backend.skill(str(name), parameters)

    def start_skill(self, name: str, **parameters: Any) -> str:
        """Starts one of the robot's skills and returns at once: for the perceptive skills that run until stopped
        (environment_modelling, localization). EXECUTING, or its final status if it ended at once."""
        return self._backend.skill(str(name), parameters, False)

    def localization(self) -> Located | None:
        """The estimate of the lab's localization (the localization skill, start_skill("localization")): where it
        believes the robot is in the lab's frame, how sure it is, whether it converged; None while none runs."""
        located = self._reading.get("localization")
        if not located:
            return None
        estimate = located.get("estimate") or {}
        return Located(float(estimate.get("x_m", 0.0)), float(estimate.get("y_m", 0.0)),
                       float(estimate.get("theta_rad", 0.0)), bool(located.get("converged")),
                       math.hypot(float(located.get("std_x_m", 0.0)), float(located.get("std_y_m", 0.0))))

    def report_pose(self, x_m: float, y_m: float) -> None:
        """Tells the grader where the code believes the robot is now (the localization exercise)."""
        self._backend.report(float(x_m), float(y_m), self._backend.now())

    # ---- sensors ----
    def odometry(self) -> Pose:
        """The odometry pose and speeds (it drifts; the grade uses the truth)."""
        odometry = self._reading.get("odometry") or {}
        pose = odometry.get("pose") or {}
        return Pose(float(pose.get("x_m", 0.0)), float(pose.get("y_m", 0.0)), float(pose.get("theta_rad", 0.0)),
                    float(odometry.get("linear_mps", 0.0)), float(odometry.get("angular_radps", 0.0)))

    def sonar(self) -> list[float]:
        """The sonar ranges [m], in the order of their mounts (the console's sonar panel shows them)."""
        return [float(r) for r in (self._reading.get("sonar") or {}).get("ranges_m", [])]

    def laser(self) -> Scan:
        """The laser scan."""
        laser = self._reading.get("laser") or {}
        return Scan(float(laser.get("angle_min_rad", 0.0)), float(laser.get("angle_increment_rad", 0.0)),
                    tuple(float(r) for r in laser.get("ranges_m", [])))

    def front_distance(self, half_angle_rad: float = 0.35) -> float:
        """The shortest laser range within half_angle_rad of straight ahead [m], from the robot's centre (the body's
        radius is BODY_RADIUS_M, 0.2 m)."""
        return self.laser().nearest(-half_angle_rad, half_angle_rad)

    def bumper(self) -> bool:
        """True when an obstacle touches the body in front or on a side (a virtual bumper from the laser)."""
        return self.laser().nearest(-1.6, 1.6) <= BODY_RADIUS_M + CONTACT_M

    def battery(self) -> float:
        """The battery's charge, 0 to 1."""
        return float((self._reading.get("battery") or {}).get("charge", 1.0))

    def line(self) -> list[float] | None:
        """The line sensor: a row of reflectance cells under the robot's front, left to right (LINE_OFFSETS_M), each
        1 over the tape and 0 on bare floor (a little noisy); None in a scene without a line of tape."""
        values = (self._reading.get("line") or {}).get("values") or []
        return [float(v) for v in values] or None

    def line_position(self, threshold: float = 0.5) -> float | None:
        """Where the tape is under the sensor [m], left positive (the cells' reflectance-weighted offset), or None
        when no cell reads above threshold (the line is lost, or the scene has none)."""
        values = self.line() or []
        seen = [(v, o) for v, o in zip(values, LINE_OFFSETS_M, strict=False) if v > threshold]
        if not seen:
            return None
        return sum(v * o for v, o in seen) / sum(v for v, _ in seen)

    def _finish(self) -> None:
        self._running = False
        self._command = (0.0, 0.0)
        self._backend.send(0.0, 0.0)


robot: Robot | None = None


def attach(backend: Backend) -> Robot:
    """Makes the module's `robot` talk to backend (the page or the tests do this before the student's code)."""
    global robot
    robot = Robot(backend)
    return robot
