"""The local farm leaves no robot behind: a start that finishes after the farm closed stops its robot, and a
robot whose web process dies ends with it."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

import pytest

from middleware.farm.base import FarmUnavailable, RobotSpec
from middleware.farm.local import LocalProcessFarm


def _skill_servers_named(name: str) -> list[str]:
    found = subprocess.run(["pgrep", "-f", f"skill_server .*--name {name} "], capture_output=True, text=True)
    return found.stdout.split()


def _gone_within(name: str, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while _skill_servers_named(name):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True


def test_a_start_that_finishes_after_close_stops_its_robot() -> None:
    farm = LocalProcessFarm(capacity=2)
    outcome: list[BaseException] = []

    def start() -> None:
        try:
            farm.start(RobotSpec("late-start", "empty", "token"))
        except BaseException as error:  # noqa: BLE001 - handed to the test
            outcome.append(error)

    starter = threading.Thread(target=start)
    starter.start()
    deadline = time.monotonic() + 30
    while not _skill_servers_named("late-start") and time.monotonic() < deadline:
        time.sleep(0.02)
    assert _skill_servers_named("late-start"), "the robot's process never started"
    farm.close()
    starter.join(60)
    assert len(outcome) == 1 and isinstance(outcome[0], FarmUnavailable)
    assert farm.robots() == []
    assert _gone_within("late-start", 10)
    with pytest.raises(FarmUnavailable, match="shutting down"):
        farm.start(RobotSpec("after-close", "empty", "token"))


def test_a_robot_ends_with_the_web_process_that_started_it() -> None:
    web_process = subprocess.Popen(
        [sys.executable, "-c", "import time; from middleware.farm.local import LocalProcessFarm; "
                               "from middleware.farm.base import RobotSpec; "
                               "LocalProcessFarm(capacity=1).start(RobotSpec('orphan-check', 'empty', 't')); "
                               "print('started', flush=True); time.sleep(600)"],
        stdout=subprocess.PIPE, text=True)
    try:
        assert web_process.stdout is not None and web_process.stdout.readline().strip() == "started"
        assert _skill_servers_named("orphan-check")
    finally:
        web_process.kill()
        web_process.wait()
        if web_process.stdout is not None:
            web_process.stdout.close()
    assert _gone_within("orphan-check", 10)
