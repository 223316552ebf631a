"""A drive command whose token the process remembers reaches the robot with no trip through the sockets' thread pool
(that pool also serves the sockets' database work: under a class's load a trip per command put the acks seconds
behind); a token the process does not remember is still asked for there."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import pytest

from benchmarks.standin_robots import StandInFleet

TOKEN = "owner-token"


@pytest.fixture(scope="module")
def robot_address() -> Iterator[str]:
    fleet = StandInFleet(1, "token-")
    try:
        yield next(iter(fleet.addresses.values()))
    finally:
        fleet.stop()


def _drive_twenty(address: str, tokens_of) -> tuple[list[str], int]:  # noqa: ANN001 - link -> a token source
    """Twenty drive commands through a Commander; the pool's calls it made and the robot's last applied sequence."""
    from middleware.access.commands import Commander
    from middleware.robots.link import RobotLink

    link = RobotLink("token-1", address)
    pooled: list[str] = []

    async def blocking(fn, *args):  # noqa: ANN001, ANN202 - the channel loop's pool, noting each trip
        pooled.append(getattr(fn, "__name__", str(fn)))
        return fn(*args)

    async def drive() -> int:
        link.set_controller(TOKEN)
        commander = Commander(link, tokens_of(link))
        applied = 0
        try:
            for sequence in range(1, 21):
                applied = (await commander.drive_async(sequence, 0.1, 0.0, blocking)).applied_sequence
        finally:
            link.close()  # its grpc.aio channel closes on this loop, before the loop ends
            await asyncio.sleep(0.1)
        return applied

    # A loop of its own on a thread of its own, as the channel loop runs: this process's main thread may hold the
    # browser tests' Playwright loop (then asyncio.run here refuses, "called from a running event loop").
    with ThreadPoolExecutor(1) as thread:
        return pooled, thread.submit(lambda: asyncio.run(drive())).result(60)


def test_a_remembered_token_drives_with_no_trip_through_the_pool(robot_address: str) -> None:
    from middleware.access.commands import OwnerToken

    pooled, applied = _drive_twenty(robot_address, lambda link: OwnerToken(link, lambda: TOKEN))
    assert applied == 20
    assert pooled == []


def test_a_holder_not_remembered_is_asked_through_the_pool(robot_address: str) -> None:
    from middleware.access.commands import HeldTokens, OwnerToken

    def tokens(link):  # noqa: ANN001, ANN202 - a class robot whose holder this process has not read lately
        return HeldTokens(OwnerToken(link, lambda: TOKEN), lambda: None, user_id=7, owner_id=7)

    pooled, applied = _drive_twenty(robot_address, tokens)
    assert applied == 20
    assert pooled == ["token"] * 20
