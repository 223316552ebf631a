"""The class wall reads a robot from the hub this worker pumps anyway: its whole telemetry while a console here
watches it, its poses hub (pose, speeds, battery, five times a second) otherwise."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import AsyncIterator
from types import SimpleNamespace

from middleware.robots.fanout import FanoutHub
from middleware.teaching.class_wall_live import _Robots
from protos.telelab.v1 import robot_pb2


class Upstream:
    """A stand-in for one of the robot's grpc.aio telemetry streams: counts its openings."""

    def __init__(self, x_m: float) -> None:
        self.x_m = x_m
        self.opened = 0
        self.cancelled = threading.Event()

    def open(self) -> AsyncIterator[object]:
        self.opened += 1
        self.cancelled.clear()
        return self._messages()

    async def _messages(self) -> AsyncIterator[object]:
        while not self.cancelled.is_set():
            message = robot_pb2.Telemetry()
            message.odometry.pose.x_m = self.x_m
            message.battery.charge = 0.8
            yield message
            await asyncio.sleep(0.01)

    def cancel(self, _stream: object) -> None:
        self.cancelled.set()


def _hub(name: str, upstream: Upstream) -> FanoutHub:
    return FanoutHub(name, upstream.open, lambda item: item, upstream.cancel)


def _rows_until(robots: _Robots, x_m: float) -> list[list[object]]:
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        rows = robots.poses()
        if rows and rows[0][1] == x_m:
            return rows
        time.sleep(0.02)
    raise AssertionError(f"no row from the hub giving x = {x_m}")


def test_the_wall_alone_reads_the_poses_hub_and_shares_a_consoles_telemetry_hub() -> None:
    telemetry, poses = Upstream(1.0), Upstream(2.0)
    link = SimpleNamespace(name="practice-s01", telemetry=_hub("t", telemetry), poses=_hub("p", poses))
    robots = _Robots(tutor_id=1, commands=None)  # type: ignore[arg-type] - find() is not used here
    seats = [{"user_id": 7, "seat_state": "ready", "robot": "practice-s01"}]
    try:
        robots.follow(seats, {7: link})  # type: ignore[dict-item]
        assert _rows_until(robots, 2.0)[0][:2] == [7, 2.0]
        assert (link.telemetry.viewer_count, link.poses.viewer_count, telemetry.opened) == (0, 1, 0)

        console = link.telemetry.subscribe()  # a console of this worker opens on the robot
        assert _rows_until(robots, 1.0)[0][6] == 0.8  # now from the console's hub, the battery beside the pose
        assert (link.telemetry.viewer_count, link.poses.viewer_count) == (2, 0)
        assert poses.cancelled.wait(2), "the poses stream goes when nobody reads it"

        console.close()
        assert _rows_until(robots, 2.0)
        assert (link.telemetry.viewer_count, link.poses.viewer_count) == (0, 1)
        assert telemetry.cancelled.wait(2), "the wall alone does not keep the whole telemetry flowing"
    finally:
        robots.close()
        link.telemetry.close()
        link.poses.close()
    assert (link.telemetry.viewer_count, link.poses.viewer_count) == (0, 0)
