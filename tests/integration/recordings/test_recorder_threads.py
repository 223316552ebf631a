"""The recorder holds no thread per recorded session and opens no second stream per robot: each session is a task on
the worker's channel loop, a subscriber of the robot's telemetry hub (the one the consoles' viewers share), whose
disk and database work runs on a small pool of fixed size. Measured with 1 and then 20 sessions recorded at once on
stand-in robots (benchmarks/standin_robots.py: grpc.aio servers speaking the robot protocol), the threads counted
from /proc (gRPC's own threads included); each of the 20 files then reads back with its robot's telemetry."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks.standin_robots import StandInFleet, StandInRobot
from tests.conftest import make_test_app

SESSIONS = 20


def _threads() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError("no Threads line")


def _settled_threads(window_s: float = 1.5) -> int:
    """The fewest threads over window_s (a pool thread that just finished a job may still be leaving)."""
    least, deadline = _threads(), time.monotonic() + window_s
    while time.monotonic() < deadline:
        time.sleep(0.05)
        least = min(least, _threads())
    return least


class _Streams:
    """How many telemetry streams each stand-in robot has open now (the class's method wrapped while the fleet
    registers its servicers)."""

    def __init__(self) -> None:
        self.open: dict[str, int] = {}
        self.most: dict[str, int] = {}


@pytest.fixture(scope="module")
def fleet_app(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[object, StandInFleet, _Streams]]:
    from middleware.recordings import recordings_of
    from tests.conftest import _let_go

    streams = _Streams()
    original = StandInRobot.StreamTelemetry

    async def counted(self, request, context):  # noqa: N802 - gRPC's method name
        streams.open[self.name] = streams.open.get(self.name, 0) + 1
        streams.most[self.name] = max(streams.most.get(self.name, 0), streams.open[self.name])
        try:
            async for message in original(self, request, context):
                yield message
        finally:
            streams.open[self.name] -= 1

    StandInRobot.StreamTelemetry = counted  # type: ignore[method-assign]
    try:
        fleet = StandInFleet(SESSIONS, prefix="rec-")
    finally:
        StandInRobot.StreamTelemetry = original  # type: ignore[method-assign]
    tmp_path = tmp_path_factory.mktemp("recorder-threads")
    app = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", fleet.robots_setting, tmp_path)
    app.config.update(RECORDINGS_ENABLED=True, RECORDINGS_DIR=str(tmp_path / "recordings"))
    try:
        yield app, fleet, streams
    finally:
        recordings_of(app).stop()
        _let_go(app)
        fleet.stop()


def _start(app, robot_names: list[str]) -> list[int]:
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.recordings import services

    with session_factory(app)() as session, session.begin():
        user = session.query(User).filter_by(username="student1").one()
        return [services.start_recording(session, user.id, name, "exercise_run").id for name in robot_names]


def _chunks_written(app, recording_ids: list[int]) -> bool:
    from middleware.recordings import files, recordings_of

    root = recordings_of(app).settings.directory
    return all(sum(1 for m in files.read_recording(root, rid) if m.topic == "/odometry") >= 5
               for rid in recording_ids)


def _wait(condition, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"{what} within {timeout_s} s"
        time.sleep(0.1)


def test_twenty_recorded_sessions_hold_no_more_threads_than_one_and_share_the_viewers_stream(fleet_app) -> None:
    from middleware.db import session_factory
    from middleware.models.recordings import Recording
    from middleware.recordings import files, recorder, recordings_of, services
    from middleware.robots.registry import robot_registry

    app, fleet, streams = fleet_app
    keeper = recordings_of(app).keeper
    names = list(fleet.addresses)
    registry = robot_registry(app)
    # A console watches the first robot's telemetry: the recorder must read the same hub, not a stream of its own.
    watching = registry.get(names[0]).telemetry.subscribe()
    try:
        first = _start(app, names[:1])
        keeper.check()
        _wait(lambda: _chunks_written(app, first), 20, "the first session was never recorded")
        one = _settled_threads()
        rest = _start(app, names[1:])
        keeper.check()
        _wait(lambda: _chunks_written(app, first + rest), 30, "the 20 sessions were never all recorded")
        many = _settled_threads()
        assert sorted(keeper.recording_now()) == sorted(first + rest)
        print(f"\nthreads: {one} with 1 session recorded, {many} with {SESSIONS}")
        # Before: 3 threads per session (its telemetry, localization and camera readers) and a sync stream's.
        # Now only the recorder's disk pool, of fixed size, may grow with the work.
        assert many - one <= recorder.IO_THREADS, f"{many - one} threads more for {SESSIONS - 1} sessions more"
        assert streams.most[names[0]] == 1, "the recorder opened a telemetry stream beside the viewers' hub"
        assert all(streams.open.get(name) == 1 for name in names), streams.open
    finally:
        watching.close()
    with session_factory(app)() as session, session.begin():
        for recording_id in first + rest:
            services.stop_recording(session, recording_id, "finished")
    keeper.check()

    def completed() -> bool:
        with session_factory(app)() as session:
            rows = session.query(Recording).filter(Recording.id.in_(first + rest)).all()
            return all(row.status == "ready" for row in rows)

    _wait(completed, 20, "the recordings were never completed")
    root = recordings_of(app).settings.directory
    for recording_id, name in zip(first + rest, names, strict=True):
        messages = files.read_recording(root, recording_id)
        odometry = [m for m in messages if m.topic == "/odometry"]
        assert len(odometry) >= 5 and {m.topic for m in messages} >= {"/odometry", "/ground_truth", "/sonar",
                                                                      "/laser", "/robot_info"}, name
        times = [m.log_time_ns for m in odometry]
        assert times == sorted(times), "samples in the order the robot captured them"
    _wait(lambda: not any(streams.open.get(name) for name in names), 10,
          "the robots' streams were not let go once nobody watched or recorded")


def test_a_slow_disk_never_holds_the_loop_the_viewers_share(fleet_app, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each second's chunk is written and fsynced on the recorder's pool: a disk that takes a whole second per flush
    leaves the channel loop (every console's sockets and hubs) answering at once."""
    import asyncio

    from middleware.db import session_factory
    from middleware.live.loop import channel_loop
    from middleware.recordings import files, recordings_of, services

    app, fleet, _ = fleet_app
    slow_flushes: list[float] = []
    original = files.PartWriter.flush

    def slow_flush(self) -> None:
        time.sleep(1.0)
        slow_flushes.append(time.monotonic())
        original(self)

    monkeypatch.setattr(files.PartWriter, "flush", slow_flush)
    recording_id = _start(app, [list(fleet.addresses)[0]])[0]
    keeper = recordings_of(app).keeper
    keeper.check()
    loop = channel_loop().loop

    async def nothing() -> None:
        return None

    lags, deadline = [], time.monotonic() + 15
    while len(slow_flushes) < 2 and time.monotonic() < deadline:  # two slow flushes, the loop pinged meanwhile
        started = time.monotonic()
        asyncio.run_coroutine_threadsafe(nothing(), loop).result(5)
        lags.append(time.monotonic() - started)
        time.sleep(0.02)
    assert len(slow_flushes) >= 2, "the recorder never flushed in the window"
    assert max(lags) < 0.5, f"the loop waited {max(lags):.2f} s while the recorder flushed"
    with session_factory(app)() as session, session.begin():
        services.stop_recording(session, recording_id, "finished")
    keeper.check()
