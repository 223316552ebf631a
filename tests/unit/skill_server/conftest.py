"""Fixtures for the robot core's unit tests: synchronously stepped worlds in small test scenes."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from skill_sim_helpers import TOKEN

from skill_server.sim.world import World


@pytest.fixture
def empty_world() -> Iterator[World]:
    """A world on a bare floor, stepped by the test, with a deadman too long to interfere."""
    with World("empty", realtime=False, deadman_timeout_s=1000.0) as world:
        world.set_controller(TOKEN)
        yield world


@pytest.fixture
def wall_world() -> Iterator[World]:
    """The robot at the origin facing a wall whose face is WALL_FACE_X_M ahead."""
    with World("test_wall", realtime=False) as world:
        yield world


@pytest.fixture
def pole_world() -> Iterator[World]:
    """The robot at the origin with a thin pole slightly off its front sonar's axis."""
    with World("test_pole", realtime=False) as world:
        yield world
