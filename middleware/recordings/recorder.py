"""The recorder, in the worker: only the tap. Each session this worker records is tapped on the process's channel
loop (live/loop.py) from the robot's fan-out hubs like any console's viewer: no thread per session and no second
stream per robot (the robot's one telemetry stream feeds its viewers and its recording alike), and a session is
recorded by the worker whose consoles watch its robot, which holds that stream anyway.

On the loop a tap only appends a reference to each new message (packed once by the hub for every viewer) to a bounded
queue (KEPT_LIMIT): constant time, whatever the message. Once a second the keeper's thread hands every tap's second,
the command notes this worker saw (command_log.py) and which robots of the open recordings this worker reaches and
watches to the worker's writer child in one pipe message (writer.py), and taps what the child answers. The child does
the rest (keeping.py): the command log, decoding, protobuf, MCAP, fsync, the goals, the claims and heartbeats in the
database, the sessions' opening, completion and sweep when elected. The loop never waits for the disk, the database,
the writer or a robot's unary call, and none of that work runs in the worker's interpreter.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import json
import logging
import struct
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable
from typing import Any

from flask import Flask
from sqlalchemy.orm import Session

from middleware.assessment.recorder import process_key
from middleware.live.loop import channel_loop
from middleware.recordings.command_log import CommandSink
from middleware.recordings.conversion import CAMERA, LOCALIZATION, TELEMETRY, Kept
from middleware.recordings.settings import RecordingSettings
from middleware.recordings.writer import WriterGone, WriterProcess, WriterRefused
from middleware.robots.fanout import FanoutHub, Subscription
from middleware.robots.link import RobotLink
from middleware.robots.registry import RobotRegistry

log = logging.getLogger(__name__)
# Telemetry (odometry, truth, sonar, laser) comes at the hub's rate: 10 samples a second (RobotLink._open_telemetry).
CAMERA_EVERY_S = 1.0  # a JPEG frame a second while someone watches the server camera...
CAMERA_EVERY_LONG_S = 5.0  # ...and one every 5 s after the session's first CAMERA_THIN_AFTER_S
CAMERA_THIN_AFTER_S = 600.0
CAMERA_HEADER_LIMIT = 4096  # a camera frame's JSON header is a few hundred bytes; the loop reads no more of a frame
TICK_S = 1.0  # the keeper hands the writer child a second (files.FLUSH_S: a crash loses at most this much)
KEPT_LIMIT = 1200  # messages a session keeps while its second waits for the writer (2 min of telemetry); then dropped
LINK_KEPT_S = 5.0  # how long the keeper trusts a robot's link it looked up (a personal robot's is a lookup)


class _HubTap:
    """The one listener this module gives a hub (a hub keeps its listeners as long as it lives): called on the hub's
    loop after each new message, it hands the message to every session tap attached, through each one's own
    subscription, so none of them misses a message (a subscription alone is latest-wins) and none waits."""

    def __init__(self) -> None:
        self.sinks: dict[Subscription[Any], Callable[[Any], None]] = {}

    def news(self) -> None:
        for subscription, sink in list(self.sinks.items()):
            message = subscription.next_message(0.0)
            if message is None:
                continue
            try:
                sink(message)
            except Exception:  # a sink's fault must never reach the hub's pump (it would reconnect the robot)
                log.exception("a recorder could not keep a message")


_taps: weakref.WeakKeyDictionary[FanoutHub[Any], _HubTap] = weakref.WeakKeyDictionary()


def _attach(hub: FanoutHub[Any], sink: Callable[[Any], None]) -> Subscription[Any]:
    """Subscribes sink to every new message of hub (on the hub's loop; starts its pump if nobody watched)."""
    tap = _taps.get(hub)
    if tap is None:
        tap = _taps[hub] = _HubTap()
        hub.listen(tap.news)
    subscription = hub.subscribe()
    subscription.next_message(0.0)  # what the hub last had (maybe long ago, before its pump stopped) is not news
    tap.sinks[subscription] = sink
    return subscription


def _detach(hub: FanoutHub[Any], subscription: Subscription[Any]) -> None:
    tap = _taps.get(hub)
    if tap is not None:
        tap.sinks.pop(subscription, None)
    subscription.close()


class SessionTap:
    """One session this worker records: its subscriptions to the robot's hubs, on the loop, and the messages kept
    since the keeper's last tick."""

    def __init__(self, recording_id: int, link: RobotLink, loop: Any = None) -> None:
        self.recording_id, self.robot_name, self._link = recording_id, link.name, link
        self._kept: deque[Kept] = deque()  # appended on the loop, taken by the keeper's thread
        self.dropped = 0  # messages past KEPT_LIMIT while the writer lagged
        self._attached: dict[str, tuple[FanoutHub[Any], Subscription[Any]]] = {}
        self._localizing = False  # a localization goal runs (the child asked the robot): its estimate is wanted
        self._camera_started = time.monotonic()
        self._last_camera_s = 0.0
        self._stopped = False
        self._loop = loop or channel_loop().loop
        self._loop.call_soon_threadsafe(self._start)

    @property
    def taps_telemetry(self) -> bool:
        """Whether it is one of the robot's telemetry hub's viewers now."""
        return TELEMETRY in self._attached

    def follow(self, localizing: bool) -> None:
        """Subscribes to, or lets go of, the localization and camera hubs as wanted now (on the loop)."""
        self._localizing = localizing
        with contextlib.suppress(RuntimeError):  # the loop has stopped: the process is ending
            self._loop.call_soon_threadsafe(self._follow_all)

    def stop(self, timeout_s: float = 2.0) -> None:
        """Lets go of every hub (on the loop; waits for it at most timeout_s)."""
        done: concurrent.futures.Future[None] = concurrent.futures.Future()

        def stop_on_loop() -> None:
            self._stopped = True
            for hub, subscription in self._attached.values():
                _detach(hub, subscription)
            self._attached.clear()
            done.set_result(None)

        try:
            self._loop.call_soon_threadsafe(stop_on_loop)
            done.result(timeout_s)
        except (RuntimeError, concurrent.futures.TimeoutError):
            log.warning("recording %s: its tap did not stop within %s s", self.recording_id, timeout_s)

    def take(self) -> list[Kept]:
        """The messages kept since the last take."""
        kept: list[Kept] = []
        with contextlib.suppress(IndexError):
            while True:
                kept.append(self._kept.popleft())
        return kept

    # On the loop.
    def _start(self) -> None:
        if self._stopped:
            return
        try:
            self._attached[TELEMETRY] = (self._link.telemetry, _attach(self._link.telemetry, self._keep_telemetry))
        except RuntimeError as error:  # the hub closed: the application is ending
            log.info("recording %s: %s", self.recording_id, error)
        self._follow_all()

    def _follow_all(self) -> None:
        if self._stopped:
            return
        self._follow(LOCALIZATION, self._link.localization, self._localizing, self._keep_localization)
        self._follow(CAMERA, self._link.camera, False, self._keep_camera)

    def _follow(self, what: str, hub: FanoutHub[Any], wanted: bool, sink: Callable[[Any], None]) -> None:
        """Subscribes to hub while wanted or while someone else in this process watches it anyway (subscribing
        alone would start its pump on the live path's loop for nothing: 200 particles packed five times a second,
        camera frames at 15 fps); unsubscribes otherwise."""
        mine = self._attached.get(what)
        others = hub.viewer_count - (1 if mine is not None else 0) > 0
        if (wanted or others) and mine is None and not hub.closed:
            self._attached[what] = (hub, _attach(hub, sink))
        elif not (wanted or others) and mine is not None:
            del self._attached[what]
            _detach(*mine)

    # The sinks: on the loop, after each new message of a hub. Each only appends a reference (constant time, whatever
    # the message: tests/integration/recordings/test_recorder_threads.py times them); the writer child reads it.
    def _keep(self, what: str, packed: Any) -> None:
        if len(self._kept) >= KEPT_LIMIT:
            self.dropped += 1  # the writer is this far behind: losing news beats holding the loop or the memory
            return
        self._kept.append((what, packed, time.time_ns()))

    def _keep_telemetry(self, packed: tuple[str, str]) -> None:
        self._keep(TELEMETRY, packed[0])  # [0]: packed with the truth (camera_pose)

    def _keep_localization(self, packed: tuple[str, str]) -> None:
        self._keep(LOCALIZATION, packed[0])

    def _keep_camera(self, packed: bytes) -> None:
        """A JPEG frame, thinned by the frames' own capture times: one a second, one every 5 s after ten minutes. Only
        the frame's small header is read here (never the JPEG behind it: the writer slices that)."""
        every = CAMERA_EVERY_S if time.monotonic() - self._camera_started < CAMERA_THIN_AFTER_S else CAMERA_EVERY_LONG_S
        if time.time() - self._last_camera_s < every:
            return  # before its header is even read
        try:
            (length,) = struct.unpack_from(">I", packed)
            header = json.loads(packed[4:4 + min(length, CAMERA_HEADER_LIMIT)])
            capture = float(header.get("capture_unix_s") or time.time())
        except (struct.error, ValueError, TypeError, AttributeError):
            return
        if capture - self._last_camera_s < every:
            return
        self._last_camera_s = capture
        self._keep(CAMERA, packed)


class RecordingKeeper:
    """The thread, in every worker, that hands its writer child a tick a second and taps the sessions it answers."""

    def __init__(self, app: Flask, sessions: Callable[[], Session], registry: RobotRegistry,
                 settings: RecordingSettings, sink: CommandSink | None = None, key: str | None = None) -> None:
        self._app = weakref.ref(app)
        self._registry, self.settings, self._sink = registry, settings, sink
        self._key = key or process_key()  # this worker, as the recorder of a session (in its rows)
        self.writer = WriterProcess(  # the child that does the recorder's work for this worker
            sessions.kw["bind"].url.render_as_string(hide_password=False),  # type: ignore[attr-defined]
            {"directory": str(settings.directory), "key": self._key, "max_total_bytes": settings.max_total_bytes,
             "max_user_bytes": settings.max_user_bytes, "retention_days": settings.retention_days})
        self._recorders: dict[int, SessionTap] = {}
        self._leftovers: dict[int, list[Kept]] = {}  # what a tap let go of kept: handed on at the next tick
        self._asked: list[str] = []  # the open recordings' robots: whether this worker reaches and watches them
        self._links: dict[str, tuple[float, RobotLink | None]] = {}
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._tick_lock = threading.Lock()
        self._paused = False

    def pause(self, paused: bool) -> None:
        """While paused this worker records nothing: its taps let go at the next tick (their sessions stay open, and
        it goes on with them in new parts once resumed). For measuring what recording costs the live path in one run
        (benchmarks/recording_cost.py)."""
        self._paused = paused

    def start(self) -> None:
        """Starts the thread once."""
        with self._lock:
            if self._thread is None and not self._stop.is_set():
                self._thread = threading.Thread(target=self._keep_forever, name="recordings", daemon=True)
                self._thread.start()

    def stop(self) -> None:
        """Stops the thread and this worker's taps; their parts are closed (their sessions stay open for another
        process)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        with self._tick_lock:
            for recording_id in list(self._recorders):
                self._let_go(recording_id)
            if self.writer.pid is not None:
                self._tick(releasing=True)
        self.writer.stop()

    def recording_now(self) -> list[int]:
        """The ids this worker records now."""
        return list(self._recorders)

    def sweep(self) -> list[int]:
        """Removes recordings past the retention or the disk limits and files no row names (in the writer child);
        the ids removed."""
        return self.writer.sweep()

    def _keep_forever(self) -> None:
        self.writer.start()  # its imports run while nothing waits for it yet
        while not self._stop.is_set():
            if self._app() is None:
                return
            try:
                self.check()
            except Exception:  # noqa: BLE001 - one failed tick must not end the keeper
                log.exception("keeping the recordings failed")
            self._stop.wait(TICK_S)

    def check(self) -> None:
        """One tick: the seconds, the notes and the robots reached to the writer child; the sessions it answers
        tapped (asked of robots it was not asked of before, it answers them at once). Starts the thread, which ticks
        once a second from then on."""
        self.start()
        with self._tick_lock:
            asked = set(self._asked)
            if self._tick() and set(self._asked) - asked:
                self._tick()

    def _tick(self, releasing: bool = False) -> bool:
        seconds = {rid: tap.take() for rid, tap in self._recorders.items()}
        for recording_id, kept in self._leftovers.items():
            seconds[recording_id] = kept + seconds.get(recording_id, [])
        self._leftovers = {}
        notes = self._sink.take() if self._sink is not None else []
        tick = {"notes": notes, "seconds": seconds, "present": self._present(), "paused": self._paused,
                "releasing": releasing}
        try:
            answer = self.writer.tick(tick)
        except WriterGone as error:  # its parts end at their last chunk; the sessions go on in new parts
            log.warning("recordings: %s", error)
            for recording_id in list(self._recorders):
                self._let_go(recording_id)
            self._leftovers = {}
            return False
        except WriterRefused as error:  # the database away for a moment: this second is lost, not the session
            log.warning("recordings: %s", error)
            if self._sink is not None:
                self._sink.put_back(notes)
            return False
        self._asked = answer["ask"]
        if not releasing:
            self._tap(answer["record"])
        return True

    def _present(self) -> dict[str, tuple[str | None, int]]:
        """For each robot asked of that this worker reaches: its address and how many of this worker's viewers
        (not its own tap) watch its telemetry."""
        tapped = {tap.robot_name for tap in self._recorders.values() if tap.taps_telemetry}
        present: dict[str, tuple[str | None, int]] = {}
        for name in self._asked:
            link = self._link(name)
            if link is not None:
                viewers = link.telemetry.viewer_count - (1 if name in tapped else 0)
                present[name] = (link.address, max(0, viewers))
        return present

    def _link(self, name: str) -> RobotLink | None:
        looked, link = self._links.get(name, (-LINK_KEPT_S, None))
        if time.monotonic() - looked >= LINK_KEPT_S:
            link = self._registry.get(name)
            self._links[name] = (time.monotonic(), link)
        return link

    def _tap(self, record: dict[int, tuple[str, bool]]) -> None:
        """Taps the sessions the child records for this worker, and lets go of the others."""
        for recording_id in [rid for rid in self._recorders if rid not in record]:
            self._let_go(recording_id)
        for recording_id, (robot_name, localizing) in record.items():
            tap = self._recorders.get(recording_id)
            if tap is None:
                link = self._link(robot_name)
                if link is None:
                    continue
                tap = self._recorders[recording_id] = SessionTap(recording_id, link)
            tap.follow(localizing)

    def _let_go(self, recording_id: int) -> None:
        tap = self._recorders.pop(recording_id)
        tap.stop()
        self._leftovers[recording_id] = tap.take()
