"""`python -m skill_server` as the middleware's CLI runs it: announces its address, stops on SIGTERM."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import grpc
from grpc_health.v1 import health_pb2, health_pb2_grpc

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

REPO_ROOT = Path(__file__).resolve().parents[3]
ANNOUNCEMENT = re.compile(r"^skill server cli-bot listening on 127\.0\.0\.1:(\d+) \(scene lab\)$")


def test_the_cli_serves_and_stops_cleanly_on_sigterm() -> None:
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "skill_server",
            "--port",
            "0",
            "--fast",
            "--name",
            "cli-bot",
            "--seed",
            "3",
            "--deadman-s",
            "1.5",
        ],
        cwd=REPO_ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout is not None
        announced = None
        for line in process.stdout:  # pybullet prints its own lines first
            announced = ANNOUNCEMENT.match(line.strip())
            if announced:
                break
        assert announced, "the server never announced its address"
        with grpc.insecure_channel(f"127.0.0.1:{announced.group(1)}") as channel:
            status = health_pb2_grpc.HealthStub(channel).Check(health_pb2.HealthCheckRequest(), timeout=10)
            assert status.status == health_pb2.HealthCheckResponse.SERVING
            info = robot_pb2_grpc.RobotStub(channel).GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=10)
            assert (info.robot_name, info.deadman_timeout_s) == ("cli-bot", 1.5)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == 0
    finally:
        if process.poll() is None:
            process.kill()
        process.communicate()


def test_the_cli_refuses_an_unknown_scene_naming_the_known_ones() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "skill_server", "--port", "0", "--scene", "nowhere"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "unknown scene 'nowhere'" in result.stderr and "lab" in result.stderr
