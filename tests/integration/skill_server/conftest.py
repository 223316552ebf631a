"""Fixtures for the skill server's integration tests: real gRPC servers on port 0 in fast mode."""

from __future__ import annotations

from collections.abc import Iterator

import grpc
import pytest

from protos.telelab.v1 import robot_pb2_grpc
from skill_server.server import SkillServer, create_server


@pytest.fixture(scope="module")
def shared_server() -> Iterator[SkillServer]:
    """One fast-mode server for tests that only read or that leave the robot as they found it."""
    running = create_server(port=0, realtime=False, deadman_timeout_s=2.0)
    yield running
    running.stop(grace_s=0.5)


@pytest.fixture
def fresh_server() -> Iterator[SkillServer]:
    """A fast-mode server of the test's own, for tests that move the robot or stop the server."""
    running = create_server(port=0, realtime=False, deadman_timeout_s=2.0, robot_name="test-bot")
    yield running
    running.stop(grace_s=0.5)


@pytest.fixture
def channel(shared_server: SkillServer) -> Iterator[grpc.Channel]:
    """A channel to the shared server."""
    with grpc.insecure_channel(shared_server.address) as channel:
        yield channel


@pytest.fixture
def robot(channel: grpc.Channel) -> robot_pb2_grpc.RobotStub:
    """A Robot stub on the shared server."""
    return robot_pb2_grpc.RobotStub(channel)
