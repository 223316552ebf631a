"""The local farm leaves no robot behind: a start that finishes after the farm closed stops its robot, and a
robot whose web process dies ends with it."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
import uuid

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
    name = f"late-{uuid.uuid4().hex[:8]}"  # a robot of this run alone, whatever another run left behind
    farm = LocalProcessFarm(capacity=2)
    outcome: list[BaseException] = []

    def start() -> None:
        try:
            farm.start(RobotSpec(name, "empty", "token"))
        except BaseException as error:  # noqa: BLE001 - handed to the test
            outcome.append(error)

    starter = threading.Thread(target=start)
    starter.start()
    deadline = time.monotonic() + 30
    while not _skill_servers_named(name) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert _skill_servers_named(name), "the robot's process never started"
    farm.close()
    starter.join(60)
    assert len(outcome) == 1 and isinstance(outcome[0], FarmUnavailable)
    assert farm.robots() == []
    assert _gone_within(name, 10)
    with pytest.raises(FarmUnavailable, match="shutting down"):
        farm.start(RobotSpec("after-close", "empty", "token"))


def test_a_robot_ends_with_the_web_process_that_started_it() -> None:
    name = f"orphan-{uuid.uuid4().hex[:8]}"
    web_process = subprocess.Popen(
        [sys.executable, "-c", "import time; from middleware.farm.local import LocalProcessFarm; "
                               "from middleware.farm.base import RobotSpec; "
                               f"LocalProcessFarm(capacity=1).start(RobotSpec('{name}', 'empty', 't')); "
                               "print('started', flush=True); time.sleep(600)"],
        stdout=subprocess.PIPE, text=True)
    try:
        assert web_process.stdout is not None and web_process.stdout.readline().strip() == "started"
        assert _skill_servers_named(name)
    finally:
        web_process.kill()
        web_process.wait()
        if web_process.stdout is not None:
            web_process.stdout.close()
    assert _gone_within(name, 10)


def test_a_fast_robot_steps_faster_than_real_time_and_is_never_restarted() -> None:
    """RobotSpec(fast=True), a plan's prediction: its world runs flat out, and a throwaway robot that dies stays
    dead (its request is over)."""
    from middleware.robots.link import RobotLink

    farm = LocalProcessFarm(capacity=1)
    try:
        robot = farm.start(RobotSpec("fast-check", "empty", "token", fast=True))
        link = RobotLink("fast-check", robot.address, rpc_timeout_s=5.0)
        stream = link.stream_poses(10.0)
        first = next(iter(stream)).sim_time_s
        began = time.monotonic()
        latest = first
        for message in stream:  # read as they come for a second of wall time
            latest = message.sim_time_s
            if time.monotonic() - began > 1.0:
                break
        stream.cancel()
        link.close()
        ratio = (latest - first) / (time.monotonic() - began)
        print(f"the fast robot ran {ratio:.1f} times faster than real time")
        assert ratio > 2.0
        pids = _skill_servers_named("fast-check")
        assert len(pids) == 1
        subprocess.run(["kill", "-9", pids[0]], check=True)
        time.sleep(2.5)  # more than the farm's restart pause
        assert _skill_servers_named("fast-check") == [], "a fast robot was restarted"
    finally:
        farm.close()
    assert _gone_within("fast-check", 10)
