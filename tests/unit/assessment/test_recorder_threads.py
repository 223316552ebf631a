"""A graded attempt's recording holds no thread of its own: it is a task on the channel loop (a stand-in link whose
telemetry is an async generator; the real grpc.aio stream is exercised by tests/integration/assessment)."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import AsyncGenerator
from types import SimpleNamespace

from middleware.assessment import recorder


class StandInLink:
    def __init__(self, name: str) -> None:
        self.name = name
        self.cancelled = threading.Event()

    async def watch_telemetry(self, rate_hz: float) -> AsyncGenerator[object, None]:
        pose = SimpleNamespace(x_m=1.0, y_m=2.0, theta_rad=0.5)
        try:
            while True:
                yield SimpleNamespace(ground_truth=pose, odometry=SimpleNamespace(pose=pose))
                await asyncio.sleep(0.01)
        finally:
            self.cancelled.set()


def test_fifty_recordings_add_no_thread_and_each_stops_with_its_samples() -> None:
    warm = recorder.TraceRecorder(StandInLink("warm"), lambda _trace: True)  # type: ignore[arg-type]
    warm.stop()  # the channel loop's thread exists from here on
    before = threading.active_count()
    links = [StandInLink(f"r{i}") for i in range(50)]
    flushed: list[int] = []
    recorders = [recorder.TraceRecorder(link, lambda trace: flushed.append(len(trace)) or True,  # type: ignore[arg-type]
                                        [[0.0, 0, 0, 0, 0, 0, 0]]) for link in links]
    deadline = time.monotonic() + 5.0
    while any(len(r.samples()) < 3 for r in recorders) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert threading.active_count() - before <= 1, [t.name for t in threading.enumerate()]
    for link, each in zip(links, recorders, strict=True):
        samples = each.stop()
        assert len(samples) >= 3 and samples[0] == [0.0, 0, 0, 0, 0, 0, 0]
        assert samples[1][0] > 0, "a recording taken over goes on after the stored trace's time"
        assert link.cancelled.wait(2.0), "stopping it ends its stream"
