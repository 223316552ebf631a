"""RobotLink.info answers pollers from a cache no older than they allow, and notices a robot gone after that."""

from __future__ import annotations

import time

import pytest

from middleware.robots.link import RobotLink, RobotUnavailable
from middleware.robots.processes import SkillServerProcess, wait_until_serving


def test_info_is_asked_again_once_older_than_max_age_and_a_stopped_robot_is_then_offline() -> None:
    robot = SkillServerProcess("lab-9", "empty")
    robot.start()
    link = RobotLink("lab-9", robot.address, rpc_timeout_s=1.0)
    try:
        wait_until_serving(robot.address)
        assert link.info(max_age_s=0.5).scene_name == "empty"
        robot.stop()
        assert link.info(max_age_s=0.5).scene_name == "empty", "within max_age the cached answer stands"
        time.sleep(0.6)
        with pytest.raises(RobotUnavailable):
            link.info(max_age_s=0.5)
        with pytest.raises(RobotUnavailable):
            link.info(refresh=True)
    finally:
        link.close()
        robot.stop()


def test_a_call_on_a_closed_link_is_an_unavailable_robot_not_a_crash() -> None:
    link = RobotLink("lab-9", "127.0.0.1:1", rpc_timeout_s=0.2)
    link.close()
    with pytest.raises(RobotUnavailable, match="closed"):
        link.measure_round_trip_ms()
