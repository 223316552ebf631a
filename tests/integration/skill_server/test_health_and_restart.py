"""Telediagnosis and telemaintenance on real skill servers: GetHealth reports the loop against real time, the
process and the faults with their times; Restart starts a robot's own process again on the same address, same pid,
keeping its controller, and refuses a wrong token or a robot living inside another program."""

from __future__ import annotations

import time

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import create_server


def _stub(address: str) -> robot_pb2_grpc.RobotStub:
    return robot_pb2_grpc.RobotStub(grpc.insecure_channel(address))


def test_health_reports_the_loop_the_process_and_a_deadman_stop_as_a_fault() -> None:
    running = create_server(port=0, realtime=True, robot_name="diag-1", controller_token="tok")
    try:
        robot = _stub(running.address)
        robot.Drive(robot_pb2.DriveCommand(token="tok", sequence=1, linear_mps=0.2), timeout=5)
        time.sleep(1.5)  # no command after the first: the deadman stops the base
        health = robot.GetHealth(robot_pb2.GetHealthRequest(), timeout=5)
        assert 0.8 <= health.real_time_factor <= 1.2, health
        assert health.version and health.pid > 0 and health.rss_bytes > 10_000_000 and health.uptime_s > 1
        assert [f.kind for f in health.faults] == ["deadman"]
        assert abs(health.faults[0].unix_s - time.time()) < 5 and "deadman stopped it" in health.faults[0].message
        assert not health.restartable, "in this process: the test would be replaced"
        with pytest.raises(grpc.RpcError) as refused:
            robot.Restart(robot_pb2.RestartRequest(token="tok"), timeout=5)
        assert refused.value.code() == grpc.StatusCode.FAILED_PRECONDITION
        assert "inside another program" in (refused.value.details() or "")
    finally:
        running.stop(grace_s=0.5)


def test_a_restart_starts_the_robots_process_again_on_its_address_keeping_its_controller() -> None:
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    process = SkillServerProcess("diag-2", "lab", echo=False, controller_token="owner")
    process.start()
    try:
        wait_until_serving(process.address)
        robot = _stub(process.address)
        robot.Drive(robot_pb2.DriveCommand(token="owner", sequence=1, linear_mps=0.1), timeout=5)
        before = robot.GetHealth(robot_pb2.GetHealthRequest(), timeout=5)
        assert before.restartable and before.restarts == 0
        with pytest.raises(grpc.RpcError) as refused:
            robot.Restart(robot_pb2.RestartRequest(token="someone else"), timeout=5)
        assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED
        answer = robot.Restart(robot_pb2.RestartRequest(token="owner"), timeout=5)
        assert answer.restarting and "restarting" in answer.message
        deadline = time.monotonic() + 30
        while True:
            try:
                after = robot.GetHealth(robot_pb2.GetHealthRequest(), timeout=2)
                if after.restarts == 1:
                    break
            except grpc.RpcError:
                pass
            assert time.monotonic() < deadline, "the robot did not answer again within 30 s"
            time.sleep(0.2)
        assert after.pid == before.pid and after.uptime_s < before.uptime_s + 30
        assert process.process is not None and process.process.poll() is None, "its supervisor sees it go on"
        assert process.restarts == 0, "the farm's watcher did not have to start it again"
        ack = robot.Drive(robot_pb2.DriveCommand(token="owner", sequence=2, linear_mps=0.0), timeout=5)
        assert ack.applied_sequence == 2, "the owner still drives it"
    finally:
        process.stop()
