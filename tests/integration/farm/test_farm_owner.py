"""The local farm's owner process, as `telelab up` runs it for its web workers: any worker process finds and
drives the robots another started; a wrong key is refused; robots end with the owner."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest

from middleware.farm.base import FarmUnavailable, RobotSpec
from middleware.farm.owner import ADDRESS_VARIABLE, KEY_VARIABLE, FarmOwner, SharedLocalFarm
from middleware.farm.setup import build_farm
from middleware.robots.link import CommandRefused, RobotLink


@pytest.fixture
def owner() -> Iterator[FarmOwner]:
    made = FarmOwner()
    made.start()
    yield made
    made.stop()


def _drives(address: str, token: str, sequence: int) -> bool:
    link = RobotLink("probe", address, rpc_timeout_s=2.0)
    try:
        return link.drive(token, sequence, 0.1, 0.0).applied_sequence == sequence
    finally:
        link.close()


def test_another_worker_process_finds_and_drives_the_robot_one_worker_started(owner: FarmOwner) -> None:
    farm = build_farm({"TELELAB_FARM": "local", ADDRESS_VARIABLE: owner.address, KEY_VARIABLE: owner.key.hex()})
    assert isinstance(farm, SharedLocalFarm)
    robot = farm.start(RobotSpec("shared-1", "empty", "token-1"))
    assert farm.start(RobotSpec("shared-1", "empty", "token-1")).address == robot.address  # the running one
    other_worker = subprocess.run(
        [sys.executable, "-c", "from middleware.farm.setup import build_farm; "
                               "print(build_farm().find('shared-1').address)"],
        env={**os.environ, ADDRESS_VARIABLE: owner.address, KEY_VARIABLE: owner.key.hex()},
        capture_output=True, text=True, timeout=60)
    assert other_worker.stdout.strip() == robot.address, other_worker.stderr
    assert _drives(robot.address, "token-1", 1)
    with pytest.raises(CommandRefused):
        _drives(robot.address, "someone-else", 2)
    assert [r.name for r in farm.robots()] == ["shared-1"] and farm.capacity().running == 1
    assert farm.stop("shared-1") and farm.find("shared-1") is None


def test_a_wrong_key_or_a_missing_owner_is_a_clear_refusal(owner: FarmOwner) -> None:
    with pytest.raises(FarmUnavailable, match="farm process is not running"):
        SharedLocalFarm(owner.address, os.urandom(32).hex()).robots()
    with pytest.raises(FarmUnavailable, match="farm process is not running"):
        SharedLocalFarm(owner.address + ".gone", owner.key.hex()).robots()


def test_the_robots_end_with_the_owner() -> None:
    made = FarmOwner()
    made.start()
    farm = SharedLocalFarm(made.address, made.key.hex())
    robot = farm.start(RobotSpec("shared-2", "empty", "token-2"))
    made.stop()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            _drives(robot.address, "token-2", 1)
        except Exception:  # noqa: BLE001 - gone is what we wait for
            return
        time.sleep(0.2)
    raise AssertionError("the robot still answers after its owner stopped")


def test_a_forked_worker_talks_to_the_owner_on_a_connection_of_its_own(owner: FarmOwner) -> None:
    """gunicorn forks its workers from the launcher, whose app asked the farm before: a worker reading the launcher's
    connection unpickled the other's answers ("invalid load key") and died at start."""
    farm = SharedLocalFarm(owner.address, owner.key.hex())
    assert farm.capacity().running == 0  # the launcher's connection, made before the fork
    children = []
    for _ in range(2):
        pid = os.fork()
        if pid == 0:  # a worker: asks as the launcher goes on asking
            code = 1
            try:
                code = 0 if all(farm.capacity().running == 0 for _ in range(200)) else 1
            finally:
                os._exit(code)
        children.append(pid)
    assert all(farm.capacity().running == 0 for _ in range(200))
    assert [os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) for pid in children] == [0, 0]
