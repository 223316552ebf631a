"""Starts, tracks and stops the personal practice robots of this process.

One PracticeManager per app and process: the robots it starts are children of this process and their
owners' tokens live in its memory. A deployment with several worker processes would need the robots'
addresses and tokens in the database (or one process owning the robots); `telelab up` runs one process.

The robot registry resolves `practice-...` names through the manager for their owners only, so a practice
robot opens in the lab console (/lab/<name>) with every panel, and every robot page, API and channel
answers anyone else with a 404.
"""

from __future__ import annotations

import logging
import os
import re
import secrets
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass

from flask import Flask, current_app

from middleware.access.commands import hand_over
from middleware.config import ConfigError
from middleware.errors import Refused
from middleware.robots.link import RobotLink
from middleware.robots.processes import SkillServerProcess, SkillServerStartError
from middleware.robots.registry import PersonalRobot, RobotRegistry

log = logging.getLogger(__name__)
_EXTENSION_KEY = "telelab.practice"
DEFAULT_CAP = 4
DEFAULT_IDLE_S = 900.0
PRACTICE_PREFIX = "practice-"
PLAIN_USERNAME = re.compile(r"^[a-z0-9][a-z0-9_-]{0,22}$")  # fits the 32-character robot names as it is


class PracticeCapReached(Refused):
    """Every practice slot is taken (429); the message says how many and what to do."""

    def __init__(self, message: str) -> None:
        super().__init__(429, "practice_cap_reached", message)


class PracticeStartFailed(Refused):
    """The practice robot's skill server did not start, or is starting already (503)."""

    def __init__(self, message: str) -> None:
        super().__init__(503, "practice_start_failed", message)


def watched(link: RobotLink) -> bool:
    """Whether someone watches one of the robot's streams now (a console open on it)."""
    return any(hub.viewer_count > 0 for hub in (link.camera, link.telemetry, link.localization))


@dataclass
class PracticeRobot:
    """One learner's robot: the process, the link, the owner's controller token (for the robot's whole life:
    nobody else can ever control it) and the last use."""

    name: str
    owner_id: int
    process: SkillServerProcess
    link: RobotLink
    token: str
    started_at: float
    last_used_at: float
    username: str = ""

    def touch(self, now: float) -> None:
        """Records a use, which keeps the robot from being stopped as idle."""
        self.last_used_at = now


def practice_name(username: str, owner_id: int) -> str:
    """The robot name of a user's practice robot: unique, URL-safe and at most 32 characters.

    `practice-<username>` when the username fits as it is; `practice-_<id>` otherwise (no username starts
    with "_", so the two forms never meet).
    """
    if PLAIN_USERNAME.fullmatch(username):
        return PRACTICE_PREFIX + username
    return f"{PRACTICE_PREFIX}_{owner_id}"


def read_limits(environ: dict[str, str] | None = None) -> tuple[int, float]:
    """TELELAB_PRACTICE_CAP and TELELAB_PRACTICE_IDLE_S, checked; the errors name the setting."""
    env = os.environ if environ is None else environ
    raw_cap, raw_idle = env.get("TELELAB_PRACTICE_CAP", str(DEFAULT_CAP)), env.get("TELELAB_PRACTICE_IDLE_S",
                                                                                   str(DEFAULT_IDLE_S))
    try:
        cap = int(raw_cap)
    except ValueError:
        raise ConfigError(f"TELELAB_PRACTICE_CAP must be a whole number, not {raw_cap!r}.") from None
    try:
        idle_s = float(raw_idle)
    except ValueError:
        raise ConfigError(f"TELELAB_PRACTICE_IDLE_S must be a number of seconds, not {raw_idle!r}.") from None
    if not 0 <= cap <= 64:
        raise ConfigError("TELELAB_PRACTICE_CAP must be between 0 and 64.")
    if not 5 <= idle_s <= 86400:
        raise ConfigError("TELELAB_PRACTICE_IDLE_S must be between 5 and 86400 seconds.")
    return cap, idle_s


class PracticeManager:
    """The practice robots of this process: at most `cap` at once, each stopped after `idle_s` unused."""

    def __init__(self, cap: int, idle_s: float, rpc_timeout_s: float = 1.0, scene: str = "lab",
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.cap, self.idle_s, self.scene = cap, idle_s, scene
        self._rpc_timeout_s = rpc_timeout_s
        self._clock = clock
        self._robots: dict[int, PracticeRobot] = {}
        self._starting: set[int] = set()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._reaper: threading.Thread | None = None

    def get(self, owner_id: int) -> PracticeRobot | None:
        """owner_id's running practice robot, if any (and counts as a use)."""
        robot = self._robots.get(owner_id)
        if robot is not None:
            robot.touch(self._clock())
        return robot

    def by_name(self, name: str) -> PracticeRobot | None:
        """The running practice robot called name, whoever owns it (the caller checks the owner)."""
        robot = next((r for r in list(self._robots.values()) if r.name == name), None)
        if robot is not None:
            robot.touch(self._clock())
        return robot

    def personal_robot(self, name: str) -> PersonalRobot | None:
        """The registry's view of the practice robot called name (its resolver)."""
        robot = self.by_name(name)
        if robot is None:
            return None
        return PersonalRobot(robot.link, f"Practice robot of {robot.username}", robot.owner_id, robot.token)

    def count(self) -> int:
        """How many practice robots run or are starting now."""
        with self._lock:
            return len(self._robots) + len(self._starting)

    def start(self, owner_id: int, username: str) -> PracticeRobot:
        """owner_id's practice robot, started now if not running; PracticeCapReached when every slot is taken."""
        with self._lock:
            existing = self._robots.get(owner_id)
            if existing is not None:
                existing.touch(self._clock())
                return existing
            if owner_id in self._starting:
                raise PracticeStartFailed("Your practice robot is starting already; wait a few seconds.")
            if len(self._robots) + len(self._starting) >= self.cap:
                raise PracticeCapReached(
                    f"All {self.cap} practice robots are in use. Try again in a few minutes, "
                    "or watch a lab robot in the meantime.")
            self._starting.add(owner_id)
        name = practice_name(username, owner_id)
        process = SkillServerProcess(name, self.scene)
        try:
            process.serve()
            link = RobotLink(name, process.address, self._rpc_timeout_s)
            token = secrets.token_urlsafe(32)
            if not hand_over(link, token):
                link.close()
                raise SkillServerStartError(f"{name} did not take its controller token.")
        except SkillServerStartError as error:
            process.stop()
            with self._lock:
                self._starting.discard(owner_id)
            log.warning("practice robot %s did not start: %s", name, error)
            raise PracticeStartFailed("Your practice robot did not start. Try again in a moment.") from None
        now = self._clock()
        robot = PracticeRobot(name, owner_id, process, link, token, now, now, username=username)
        with self._lock:
            self._starting.discard(owner_id)
            self._robots[owner_id] = robot
        self.start_reaper()
        return robot

    def stop(self, owner_id: int) -> bool:
        """Stops owner_id's practice robot; False when there was none."""
        with self._lock:
            robot = self._robots.pop(owner_id, None)
        if robot is None:
            return False
        robot.link.close()
        robot.process.stop()
        return True

    def stop_idle(self) -> list[str]:
        """Stops every robot unused for idle_s (a console watching it counts as a use); returns their names."""
        now = self._clock()
        with self._lock:
            robots = list(self._robots.values())
        for robot in robots:
            if watched(robot.link):
                robot.touch(now)
        with self._lock:
            idle = [r for r in self._robots.values() if now - r.last_used_at >= self.idle_s]
        for robot in idle:
            log.info("stopping idle practice robot %s", robot.name)
            self.stop(robot.owner_id)
        return [r.name for r in idle]

    def shutdown(self) -> None:
        """Stops the reaper and every practice robot (application shutdown)."""
        self._stop.set()
        for owner_id in list(self._robots):
            self.stop(owner_id)
        if self._reaper is not None:
            self._reaper.join(5)

    def start_reaper(self) -> None:
        """Checks for idle robots in the background."""
        with self._lock:
            if self._reaper is not None or self._stop.is_set():
                return
            self._reaper = threading.Thread(target=self._reap_forever, name="practice-reaper", daemon=True)
            self._reaper.start()

    def _reap_forever(self) -> None:
        interval_s = min(10.0, max(0.5, self.idle_s / 4))
        while not self._stop.wait(interval_s):
            try:
                self.stop_idle()
            except Exception:  # noqa: BLE001 - one failed stop must not end the reaper
                log.exception("stopping idle practice robots failed")


_managers: weakref.WeakSet[PracticeManager] = weakref.WeakSet()


def _stop_all_at_exit() -> None:
    for manager in _managers:
        manager.shutdown()


def init_app(app: Flask, registry: RobotRegistry) -> None:
    """Creates app's manager from TELELAB_PRACTICE_CAP / TELELAB_PRACTICE_IDLE_S (or PRACTICE_* in config)."""
    import atexit

    cap, idle_s = read_limits()
    manager = PracticeManager(int(app.config.get("PRACTICE_CAP", cap)),
                              float(app.config.get("PRACTICE_IDLE_S", idle_s)),
                              float(app.config["ROBOT_RPC_TIMEOUT_S"]))
    app.extensions[_EXTENSION_KEY] = manager
    registry.set_personal(PRACTICE_PREFIX, manager.personal_robot)
    if not _managers:
        atexit.register(_stop_all_at_exit)  # practice robots are children: never leave them behind
    _managers.add(manager)


def practice_manager(app: Flask | None = None) -> PracticeManager:
    """The practice manager of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
