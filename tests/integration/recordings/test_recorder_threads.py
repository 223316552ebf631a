"""The recorder holds no thread per recorded session and opens no second stream per robot: each session is a tap on
the worker's channel loop, a subscriber of the robot's telemetry hub (the one the consoles' viewers share), whose
disk and database work runs in the worker's writer child. Across workers a session is recorded by the worker whose
consoles watch its robot, and a killed worker's session goes on in another. Measured with 1 and then 20 sessions
recorded at once on stand-in robots (benchmarks/standin_robots.py: grpc.aio servers speaking the robot protocol),
the threads counted from /proc (gRPC's own threads included); each of the 20 files then reads back with its robot's
telemetry."""

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
    from middleware.recordings.parts import recordings_of
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
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

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
    from middleware.recordings import files, services
    from middleware.recordings.parts import recordings_of
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
        # Before: 3 threads per session (its telemetry, localization and camera readers) and a sync stream's; then a
        # pool of 4 for the recorders' database and robot calls. Now the worker only taps: the rest is its child's.
        assert many - one <= 0, f"{many - one} threads more for {SESSIONS - 1} sessions more"
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
    """Each second's chunk is written and fsynced by the writer child, which the keeper's thread waits for: a disk
    that takes a whole second per flush leaves the channel loop (every console's sockets and hubs) answering at
    once."""
    import asyncio

    from middleware.db import session_factory
    from middleware.live.loop import channel_loop
    from middleware.recordings import services
    from middleware.recordings.parts import recordings_of
    from middleware.recordings.writer import WriterProcess

    app, fleet, _ = fleet_app
    slow_flushes: list[float] = []
    original = WriterProcess.tick

    def slow_tick(self, *args, **kwargs):  # the writer child's second (chunk, fsync) seen from here: a slow disk
        time.sleep(1.0)
        slow_flushes.append(time.monotonic())
        return original(self, *args, **kwargs)

    monkeypatch.setattr(WriterProcess, "tick", slow_tick)
    recording_id = _start(app, [list(fleet.addresses)[0]])[0]
    keeper = recordings_of(app).keeper
    keeper.check()
    loop = channel_loop().loop

    async def nothing() -> None:
        return None

    _wait(lambda: recording_id in keeper.recording_now(), 20, "the session was never recorded")
    flushed, lags, deadline = len(slow_flushes), [], time.monotonic() + 15
    while len(slow_flushes) < flushed + 2 and time.monotonic() < deadline:  # two slow flushes, the loop pinged
        started = time.monotonic()
        asyncio.run_coroutine_threadsafe(nothing(), loop).result(5)
        lags.append(time.monotonic() - started)
        time.sleep(0.02)
    assert len(slow_flushes) >= flushed + 2, "the recorder never flushed in the window"
    assert max(lags) < 0.5, f"the loop waited {max(lags):.2f} s while the recorder flushed"
    with session_factory(app)() as session, session.begin():
        services.stop_recording(session, recording_id, "finished")
    keeper.check()


def _recorder_of(app, recording_id: int, name: str, timeout_s: float = 20):
    """The session's recorder once it taps the robot's telemetry hub, and its telemetry sink."""
    from middleware.recordings import recorder
    from middleware.recordings.parts import recordings_of
    from middleware.robots.registry import robot_registry

    keeper = recordings_of(app).keeper
    hub = robot_registry(app).get(name).telemetry
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        keeper.check()
        session = keeper._recorders.get(recording_id)  # noqa: SLF001 - the recorder under test
        tap = recorder._taps.get(hub)  # noqa: SLF001
        sinks = [sink for sink in (tap.sinks.values() if tap else ()) if getattr(sink, "__self__", None) is session]
        if sinks:
            return session, sinks[0]
        time.sleep(0.1)
    raise AssertionError(f"recording {recording_id} never tapped {name}'s telemetry within {timeout_s} s")


def _stop(app, recording_id: int) -> None:
    from middleware.db import session_factory
    from middleware.recordings import services
    from middleware.recordings.parts import recordings_of

    with session_factory(app)() as session, session.begin():
        services.stop_recording(session, recording_id, "finished")
    recordings_of(app).keeper.check()


def test_the_tap_keeps_a_message_in_constant_time_whatever_its_size_and_however_slow_the_writer(
        fleet_app, monkeypatch: pytest.MonkeyPatch) -> None:
    """On the loop a recorder only keeps a reference to each message: a 1 MB message costs the loop what a 30-byte
    one does (decoding, encoding or copying it there would cost it milliseconds), and while the writer lags its list
    stops at KEPT_LIMIT (the rest counted as dropped) instead of growing. Minimum and median of 300 calls of each
    size, interleaved, timed on the loop itself (a preempted call moves neither)."""
    import asyncio
    import statistics

    from middleware.live.loop import channel_loop
    from middleware.recordings import recorder
    from middleware.recordings.writer import WriterProcess

    app, fleet, _ = fleet_app
    original = WriterProcess.tick

    def stalled_tick(self, *args, **kwargs):
        time.sleep(3.0)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(WriterProcess, "tick", stalled_tick)
    monkeypatch.setattr(recorder, "KEPT_LIMIT", 400)
    name = list(fleet.addresses)[2]
    recording_id = _start(app, [name])[0]
    session, sink = _recorder_of(app, recording_id, name)
    small = ('{"capture_unix_s":0}', "")
    big = ('{"capture_unix_s":0,"pad":"' + "x" * 1_000_000 + '"}', "")

    async def timed() -> dict[str, list[float]]:
        times: dict[str, list[float]] = {"small": [], "big": []}
        for _ in range(300):
            for size, message in (("small", small), ("big", big)):
                started = time.perf_counter()
                sink(message)
                times[size].append(time.perf_counter() - started)
        return times

    times = asyncio.run_coroutine_threadsafe(timed(), channel_loop().loop).result(30)
    kept, dropped = len(session._kept), session.dropped  # noqa: SLF001
    _stop(app, recording_id)
    small_min, big_min = min(times["small"]), min(times["big"])
    small_median, big_median = statistics.median(times["small"]), statistics.median(times["big"])
    print(f"\ntap per message: 30 B min {small_min * 1e6:.2f} us, median {small_median * 1e6:.2f} us; "
          f"1 MB min {big_min * 1e6:.2f} us, median {big_median * 1e6:.2f} us; kept {kept}, dropped {dropped}")
    assert big_min <= 5 * small_min + 5e-6, "the tap's time grows with the message: work on the loop"
    assert big_median <= 5 * small_median + 20e-6, "the tap's time grows with the message: work on the loop"
    assert kept <= 400 and dropped >= 600 - 400, "a lagging writer's messages wait in a bounded list"


def test_a_killed_writer_loses_at_most_its_last_second_and_the_session_goes_on_in_a_new_part(fleet_app) -> None:
    """The writer child is killed (SIGKILL) mid-session: its part reads back up to the second before the kill (each
    second's chunk was written and fsynced before the recorder moved on), and the session goes on in a new part
    with a new writer, completed when it ends."""
    import os
    import signal

    from middleware.db import session_factory
    from middleware.models.recordings import Recording
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

    app, fleet, _ = fleet_app
    keeper = recordings_of(app).keeper
    name = list(fleet.addresses)[3]
    recording_id = _start(app, [name])[0]
    _recorder_of(app, recording_id, name)
    root = recordings_of(app).settings.directory
    _wait(lambda: sum(1 for m in files.read_recording(root, recording_id) if m.topic == "/odometry") >= 20, 20,
          "two seconds of the session were never written")
    pid, starts = keeper.writer.pid, keeper.writer.starts
    assert pid is not None
    os.kill(pid, signal.SIGKILL)
    killed_ns = time.time_ns()

    def taken_up_again() -> bool:
        keeper.check()
        return keeper.writer.starts > starts and len(files.part_paths(root, recording_id)) >= 2
    _wait(taken_up_again, 20, "the session never went on in a new part")
    _wait(lambda: len([m for m in files.read_part(files.part_paths(root, recording_id)[-1])
                       if m.topic == "/odometry"]) >= 10, 20, "the new part was never written")
    _stop(app, recording_id)

    def completed() -> bool:
        with session_factory(app)() as session:
            row = session.get(Recording, recording_id)
            return row is not None and row.status == "ready"
    _wait(completed, 20, "the recording was never completed")
    first = [m.log_time_ns for m in files.read_part(files.part_paths(root, recording_id)[0]) if m.topic == "/odometry"]
    lost_s = (killed_ns - max(first)) / 1e9
    print(f"\nkilled writer: its part ends {lost_s:.2f} s before the kill")
    # A second in progress, and the loop's second cadence plus the pool's turn on a loaded machine.
    assert lost_s <= 2.5, f"the killed writer's part ends {lost_s:.2f} s before the kill"
    odometry = [m.log_time_ns for m in files.read_recording(root, recording_id) if m.topic == "/odometry"]
    assert odometry == sorted(odometry) and odometry[-1] > killed_ns, "the session went on after the kill"


def _recorder_key(app, recording_id: int) -> str:
    from middleware.db import session_factory
    from middleware.models.recordings import Recording

    with session_factory(app)() as session:
        return session.get(Recording, recording_id).recorder_key or ""


def _second_worker(app, key: str):
    """Another worker of the cluster in this process: links and hubs of its own (its consoles' streams), a keeper
    with a key of its own and its own writer child, over the same database and recordings directory."""
    from middleware.db import session_factory
    from middleware.recordings.parts import recordings_of
    from middleware.recordings.recorder import RecordingKeeper
    from middleware.robots.registry import RobotRegistry

    registry = RobotRegistry(app.config["ROBOTS"], app.config["ROBOT_RPC_TIMEOUT_S"])
    keeper = RecordingKeeper(app, session_factory(app), registry, recordings_of(app).settings, key=key)
    return keeper, registry


def _odometry_ns(app, recording_id: int) -> list[int]:
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

    root = recordings_of(app).settings.directory
    return [m.log_time_ns for m in files.read_recording(root, recording_id) if m.topic == "/odometry"]


def test_a_session_is_recorded_where_its_robot_is_streamed_and_a_killed_workers_sessions_go_on_elsewhere(
        fleet_app) -> None:
    """Two workers share the database: this app's (A, elected: SQLite elects every process) and B, whose console
    watches robot X. B records X's session on the stream its console holds, and X never gets a second stream (before,
    the elected A opened one of its own for every session). Robot Y, which nobody watches, is recorded by A over a
    stream of its own (or by B: SQLite elects every process) until B's console opens on Y: B takes the session over
    on its console's stream, and the stream of its own closes. Then B is killed
    (its writer child SIGKILLed, its sockets gone, no clean-up): A goes on with both sessions in new parts."""
    import os
    import signal

    from middleware.db import session_factory
    from middleware.models.recordings import Recording
    from middleware.recordings import files, keeping
    from middleware.recordings.parts import recordings_of

    app, fleet, streams = fleet_app
    a = recordings_of(app).keeper
    a.check()  # A ticks once a second from now on (it may have since an earlier test)
    b, registry_b = _second_worker(app, "worker-b:2")
    x, y = list(fleet.addresses)[5:7]
    console_x = registry_b.get(x).telemetry.subscribe()
    console_y = None
    root = recordings_of(app).settings.directory
    try:
        b.check()
        _wait(lambda: streams.open.get(x) == 1, 10, "B's console never streamed X")
        rx = _start(app, [x])[0]
        _wait(lambda: rx in b.recording_now() and len(_odometry_ns(app, rx)) >= 10, 40, "B never recorded X")
        time.sleep(2 * keeping.SOLO_AFTER_S)  # A has seen the session for a while: it leaves it to B
        assert rx not in a.recording_now()
        assert streams.most[x] == 1, "a worker opened a second stream of X to record it"

        ry = _start(app, [y])[0]
        # SQLite elects every process, so A or B, whichever ticks first once SOLO_AFTER_S passed, records Y alone.
        _wait(lambda: (ry in a.recording_now()) != (ry in b.recording_now()) and len(_odometry_ns(app, ry)) >= 10,
              40, "no worker recorded Y")
        assert _recorder_key(app, ry).endswith(keeping.SOLO) and streams.open.get(y) == 1
        y_parts = 3 if ry in a.recording_now() else 2  # B, recording Y alone, goes on in its part once it watches Y
        console_y = registry_b.get(y).telemetry.subscribe()
        _wait(lambda: ry in b.recording_now() and ry not in a.recording_now() and streams.open.get(y) == 1
              and not _recorder_key(app, ry).endswith(keeping.SOLO), 20,
              "B never recorded Y on its console's stream instead of a stream of its own")

        b._stop.set()  # noqa: SLF001 - B is killed: its keeper's thread, its writer child, its sockets
        b._thread.join(5)  # noqa: SLF001
        os.kill(b.writer.pid, signal.SIGKILL)
        for tap in list(b._recorders.values()):  # noqa: SLF001
            tap.stop()
        console_x.close()
        console_y.close()
        killed_ns = time.time_ns()
        _wait(lambda: {rx, ry} <= set(a.recording_now()), 10 + keeping.STALE_S, "A never went on with B's sessions")
        _wait(lambda: all(max(_odometry_ns(app, rid)) > killed_ns + 1e9 for rid in (rx, ry)), 20,
              "the sessions were never written after the kill")
        assert streams.open.get(x) == 1 and streams.open.get(y) == 1
    finally:
        console_x.close()
        if console_y is not None:
            console_y.close()
        b.stop()
        registry_b.close()
    _stop(app, rx)
    _stop(app, ry)

    def completed() -> bool:
        with session_factory(app)() as session:
            return all(session.get(Recording, rid).status == "ready" for rid in (rx, ry))

    _wait(completed, 20, "the recordings were never completed")
    parts_x = [p.name for p in files.part_paths(root, rx)]
    assert len(parts_x) == 2 and "worker-b_2" in parts_x[0] and "worker-b" not in parts_x[1], parts_x
    assert len(files.part_paths(root, ry)) == y_parts, "(A's,) B's from its console on, A's after B died"
    for rid in (rx, ry):
        odometry = _odometry_ns(app, rid)
        assert odometry == sorted(odometry) and len(odometry) == len(set(odometry)), "every sample once, in order"
