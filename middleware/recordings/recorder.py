"""The recorder: one process of the cluster (elected like the access ticker) records every open session, each a task
on the process's channel loop (live/loop.py) subscribed to the robot's fan-out hubs like any console's viewer: no
thread per session and no second stream per robot (the robot's one telemetry stream feeds its viewers and its
recording alike).

On the loop a session only keeps a reference to each new message (packed once by the hub for every viewer); once a
second it hands that second's messages to the recorder's pool (IO_THREADS threads for the whole process), which
decodes them, writes them to the MCAP part, closes the chunk (fsync), copies the commands other workers logged,
notes goal changes and tells the database it is alive. The loop never waits for the disk, the database or a unary
call to the robot. A session that ended is completed (footer, size, counts); a session whose recorder died (its
process, or the election moved) is continued by the new leader in a new part. The command path only queues a note
(command_log.py).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import threading
import time
import weakref
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

from flask import Flask
from sqlalchemy import select, update
from sqlalchemy.orm import Session

from middleware.assessment.recorder import process_key
from middleware.live.loop import channel_loop
from middleware.locking import ClusterElection, rows_matched
from middleware.models.accounts import as_utc, utc_now
from middleware.models.recordings import RecordedCommand, Recording
from middleware.recordings import channels, files, services
from middleware.recordings.settings import RecordingSettings
from middleware.robots.fanout import FanoutHub, Subscription
from middleware.robots.link import RobotLink
from middleware.robots.messages import unpack_camera_frame
from middleware.robots.registry import RobotRegistry
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
# Telemetry (odometry, truth, sonar, laser) comes at the hub's rate: 10 samples a second (RobotLink._open_telemetry).
CAMERA_EVERY_S = 1.0  # a JPEG frame a second while someone watches the server camera...
CAMERA_EVERY_LONG_S = 5.0  # ...and one every 5 s after the session's first CAMERA_THIN_AFTER_S
CAMERA_THIN_AFTER_S = 600.0
CHECK_S = 0.5  # how often the keeper looks at the sessions
STALE_S = 5.0  # a recording not heard of for this long lost its recorder
SWEEP_S = 60.0  # retention and disk limits
COMMANDS_SETTLE_S = 0.7  # at a session's end: the other workers' command logs write every 0.5 s
IO_THREADS = 4  # the process's threads for every session's file, database and robot calls (not one per session)
RECORDINGS_LOCK = 0x7E1E_5EC0

_TELEMETRY, _LOCALIZATION, _CAMERA = "telemetry", "localization", "camera"


def _ns(unix_s: float) -> int:
    return int(unix_s * 1e9)


_pools: dict[int, ThreadPoolExecutor] = {}
_pools_lock = threading.Lock()


def io_pool() -> ThreadPoolExecutor:
    """This process's pool for the recorders' blocking work (a forked worker makes its own)."""
    pid = os.getpid()
    with _pools_lock:
        pool = _pools.get(pid)
        if pool is None:
            _pools.clear()
            pool = _pools[pid] = ThreadPoolExecutor(IO_THREADS, thread_name_prefix="recorder-io")
        return pool


class _HubTap:
    """The one listener this module gives a hub (a hub keeps its listeners as long as it lives): called on the hub's
    loop after each new message, it hands the message to every session recorder attached, through each one's own
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


Kept = tuple[str, Any, int]  # (what, the hub's packed message or the camera's (header, jpeg), received unix ns)


class SessionRecorder:
    """Records one session until its row ends (then completes the file) or this process stops recording it."""

    def __init__(self, recording: Recording, link: RobotLink, root: Path, sessions: Callable[[], Session],
                 key: str, loop: asyncio.AbstractEventLoop | None = None) -> None:
        self.recording_id, self._link, self._sessions, self._key = recording.id, link, sessions, key
        self._root = root
        part = files.new_part_path(root, recording.id, key)
        self._started_unix_s = as_utc(recording.started_at).timestamp()
        self._writer = files.PartWriter(part, {
            "recording_id": str(recording.id), "robot": recording.robot_name, "user_id": str(recording.user_id),
            "kind": recording.kind, "started_at": as_utc(recording.started_at).isoformat(), "recorder": key})
        self._command_cursor = 0
        self._goals: dict[str, int] | None = None  # None until the first look: goals ended before are not ours
        self._counts = {"commands": 0, "skills": 0, "plans": 0}
        self._user_id = recording.user_id
        self._plan_names: list[str] = []
        self._context_written = False
        self._localizing = False  # a localization goal runs: its estimate is worth a subscription
        self._kept: list[Kept] = []  # this second's messages, appended on the loop, written by the pool
        self._camera_started = time.monotonic()
        self._last_camera_s = 0.0
        self._abandon = threading.Event()
        self._done = threading.Event()
        self._wake: asyncio.Event | None = None
        self._loop = loop or channel_loop().loop
        self._io = io_pool()
        self._future = asyncio.run_coroutine_threadsafe(self._run(), self._loop)

    @property
    def running(self) -> bool:
        """Whether it still records (or is still completing its file)."""
        return not self._done.is_set()

    def abandon(self, wait: bool = True) -> None:
        """Stops recording without completing the session (another process goes on with it); waits (at most 3 s)
        for the part to be closed when wait."""
        self._abandon.set()
        with contextlib.suppress(RuntimeError):  # the loop has stopped: the process is ending
            self._loop.call_soon_threadsafe(self._wake_up)
        if wait:
            self.wait_closed(3.0)

    def wait_closed(self, timeout_s: float) -> bool:
        """Waits until its part is closed or completed; whether it was."""
        return self._done.wait(timeout_s)

    def _wake_up(self) -> None:
        if self._wake is not None:
            self._wake.set()

    def _take(self) -> list[Kept]:
        kept, self._kept = self._kept, []
        return kept

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        self._wake = asyncio.Event()
        ended = False
        attached: dict[str, tuple[FanoutHub[Any], Subscription[Any]]] = {}
        try:
            attached[_TELEMETRY] = (self._link.telemetry, _attach(self._link.telemetry, self._keep_telemetry))
            while not self._abandon.is_set():
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._wake.wait(), files.FLUSH_S)
                if self._abandon.is_set():
                    break
                ended = not await loop.run_in_executor(self._io, self._each_second, self._take())
                if ended:
                    break
                self._follow(attached, _LOCALIZATION, self._link.localization, self._localizing,
                             self._keep_localization)
                self._follow(attached, _CAMERA, self._link.camera, False, self._keep_camera)
        except Exception as error:  # noqa: BLE001 - the hub closed, the database away: the keeper starts a new part
            if not self._abandon.is_set():
                log.warning("recording %s on %s stopped: %s", self.recording_id, self._link.name, error)
        finally:
            for hub, subscription in attached.values():
                _detach(hub, subscription)
            try:
                if ended:
                    await asyncio.sleep(COMMANDS_SETTLE_S)
                    await loop.run_in_executor(self._io, self._complete, self._take())
                else:
                    await loop.run_in_executor(self._io, self._close, self._take())
            except Exception:
                log.exception("recording %s: closing its part failed", self.recording_id)
            finally:
                self._done.set()

    def _follow(self, attached: dict[str, tuple[FanoutHub[Any], Subscription[Any]]], what: str,
                hub: FanoutHub[Any], wanted: bool, sink: Callable[[Any], None]) -> None:
        """Subscribes to hub while wanted or while someone else in this process watches it anyway (subscribing
        alone would start its pump on the live path's loop for nothing: 200 particles packed five times a second,
        camera frames at 15 fps); unsubscribes otherwise."""
        mine = attached.get(what)
        others = hub.viewer_count - (1 if mine is not None else 0) > 0
        if (wanted or others) and mine is None and not hub.closed:
            attached[what] = (hub, _attach(hub, sink))
        elif not (wanted or others) and mine is not None:
            del attached[what]
            _detach(*mine)

    # The sinks: on the loop, after each new message of a hub; they only keep a reference.
    def _keep_telemetry(self, packed: tuple[str, str]) -> None:
        self._kept.append((_TELEMETRY, packed[0], time.time_ns()))  # [0]: packed with the truth (camera_pose)

    def _keep_localization(self, packed: tuple[str, str]) -> None:
        self._kept.append((_LOCALIZATION, packed[0], time.time_ns()))

    def _keep_camera(self, packed: bytes) -> None:
        """A JPEG frame, thinned by the frames' own capture times: one a second, one every 5 s after ten minutes."""
        every = CAMERA_EVERY_S if time.monotonic() - self._camera_started < CAMERA_THIN_AFTER_S else CAMERA_EVERY_LONG_S
        if time.time() - self._last_camera_s < every:
            return  # before its header is even read
        header, jpeg = unpack_camera_frame(packed)
        capture = float(header.get("capture_unix_s") or time.time())  # type: ignore[arg-type]
        if capture - self._last_camera_s < every:
            return
        self._last_camera_s = capture
        self._kept.append((_CAMERA, (header, jpeg), _ns(capture)))

    # On the pool: the file, the database, the robot's unary calls.
    def _each_second(self, kept: list[Kept]) -> bool:
        """Writes the second's messages, copies new commands, notes goal changes, closes the chunk, heartbeats;
        False once the session ended."""
        if not self._context_written:
            self._write_context()
        self._write_kept(kept)
        self._copy_commands(until_unix_s=None)
        self._note_goals()
        self._writer.flush()
        with self._sessions() as session, session.begin():
            alive = rows_matched(session, update(Recording).where(
                Recording.id == self.recording_id, Recording.recorder_key == self._key,
                Recording.ended_at.is_(None)).values(heard_at=utc_now()))
            if alive:
                return True
            row = session.get(Recording, self.recording_id)
            if row is None or row.recorder_key != self._key:
                self._abandon.set()  # deleted, or another process took it over
                return True
            return False

    def _write_context(self) -> None:
        """The robot's description and its scene, once (the replay redraws the views from them)."""
        now_ns = time.time_ns()
        try:
            info = self._link.info()
        except Exception as error:  # noqa: BLE001 - the robot away for a second: next second
            log.info("recording %s: no robot description yet (%s)", self.recording_id, error)
            return
        self._writer.write(channels.ROBOT_INFO, info, now_ns)
        self._context_written = True
        try:
            self._writer.write(channels.SCENE, self._link.scene(max_age_s=60.0), now_ns)
        except Exception as error:  # noqa: BLE001 - a robot with no scene: the replay draws the map alone
            log.info("recording %s: no scene (%s)", self.recording_id, error)

    def _write_kept(self, kept: list[Kept]) -> None:
        for what, payload, received_ns in kept:
            if what == _TELEMETRY:
                self._write_telemetry(payload, received_ns)
            elif what == _LOCALIZATION:
                update_message = _localization_from_packed(payload)
                if update_message is not None and update_message.active:
                    self._writer.write(channels.LOCALIZATION, update_message, received_ns)
            elif what == _CAMERA:
                header, jpeg = payload
                frame = robot_pb2.CameraFrame(
                    frame_sequence=int(header.get("frame_sequence") or 0),
                    capture_unix_s=float(header.get("capture_unix_s") or 0.0),
                    width_px=int(header.get("width_px") or 0), height_px=int(header.get("height_px") or 0), jpeg=jpeg)
                self._writer.write(channels.CAMERA, frame, received_ns)

    def _write_telemetry(self, packed: str, received_ns: int) -> None:
        """One telemetry message as the hub packed it for viewers (with the truth's pose) back into the robot's
        messages: the poses exactly, sonar and laser ranges to the 0.1 mm the hub keeps."""
        try:
            message = json.loads(packed)
        except ValueError:
            return
        capture = message.get("capture_unix_s")
        at = _ns(capture) if isinstance(capture, int | float) and capture > 0 else received_ns
        odometry = message.get("odometry") or {}
        sonar = message.get("sonar") or {}
        laser = message.get("laser") or {}
        self._writer.write(channels.ODOMETRY, robot_pb2.Odometry(
            pose=_pose(odometry.get("pose")), linear_mps=_number(odometry.get("linear_mps")),
            angular_radps=_number(odometry.get("angular_radps"))), at)
        self._writer.write(channels.GROUND_TRUTH, _pose(message.get("camera_pose")), at)
        self._writer.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=_numbers(sonar.get("ranges_m"))), at)
        self._writer.write(channels.LASER, robot_pb2.LaserScan(
            angle_min_rad=_number(laser.get("angle_min_rad")),
            angle_increment_rad=_number(laser.get("angle_increment_rad")),
            ranges_m=_numbers(laser.get("ranges_m"))), at)

    def _close(self, kept: list[Kept]) -> None:
        """Abandoned or broken: what was kept goes in, and the part is closed without a summary."""
        with contextlib.suppress(Exception):
            self._write_kept(kept)
        self._writer.close()

    def _copy_commands(self, until_unix_s: float | None) -> None:
        with self._sessions() as session:
            c = RecordedCommand
            query = (select(c.id, c.sent_unix_s, c.user_id, c.sequence, c.source, c.action, c.detail, c.accepted,
                            c.outcome)  # rows, not objects: a second of a pad's commands is fifty of them
                     .where(RecordedCommand.robot_name == self._link.name,
                                                   RecordedCommand.id > self._command_cursor,
                                                   RecordedCommand.sent_unix_s >= self._started_unix_s - 0.5)
                     .order_by(RecordedCommand.id))
            if until_unix_s is not None:
                query = query.where(RecordedCommand.sent_unix_s <= until_unix_s)
            rows = list(session.execute(query))
        for row in rows:
            self._command_cursor = max(self._command_cursor, row.id)
            detail = _json_object(row.detail)
            record = channels.CommandRecord(
                sent_unix_s=row.sent_unix_s, user_id=row.user_id or 0, sequence=row.sequence, source=row.source,
                action=row.action, linear_mps=_number(detail.get("linear_mps")),
                angular_radps=_number(detail.get("angular_radps")), skill=str(detail.get("skill", "")),
                parameters_json=json.dumps(detail.get("parameters", {})), plan_name=str(detail.get("plan_name", "")),
                accepted=row.accepted, outcome=row.outcome)
            self._writer.write(channels.COMMANDS, record, _ns(row.sent_unix_s))
            self._counts["commands"] += 1
            if row.accepted and row.action == "activate" and detail.get("skill") != "direct_control":
                self._counts["skills"] += 1
            if row.accepted and row.action == "run_plan":
                self._counts["plans"] += 1
                self._plan_names.append(str(detail.get("plan_name", "")))

    def _note_goals(self) -> None:
        try:
            goals = self._link.goals()
        except Exception:  # noqa: BLE001 - the robot busy or away for a second: next second
            return
        running = (robot_pb2.GOAL_STATUS_ACCEPTED, robot_pb2.GOAL_STATUS_EXECUTING)
        self._localizing = any("localization" in goal.skill and goal.status in running for goal in goals)
        if self._goals is None:
            # The robot lists the goals of whoever used it before, ended: they are not this session's (nor its
            # person's to read); only the ones running now, and every later change, are recorded.
            self._goals = {goal.goal_id: goal.status for goal in goals if goal.status not in running}
        for goal in goals:
            if self._goals.get(goal.goal_id) != goal.status:
                self._goals[goal.goal_id] = goal.status
                self._writer.write(channels.GOALS, goal, time.time_ns())

    def _complete(self, kept: list[Kept]) -> None:
        """The session ended: its last messages, the commands up to its end, the footer, the size and the counts
        (COMMANDS_SETTLE_S after the end, for the other workers' command logs)."""
        self._write_kept(kept)
        with self._sessions() as session:
            row = session.get(Recording, self.recording_id)
            ended_unix_s = as_utc(row.ended_at).timestamp() if row is not None and row.ended_at else time.time()
        self._copy_commands(until_unix_s=ended_unix_s + 0.05)
        self._note_goals()
        self._writer.finish()
        with self._sessions() as session, session.begin():
            row = session.get(Recording, self.recording_id)
            if row is not None:
                row.status = "ready"
                row.command_count += self._counts["commands"]
                row.skill_count += self._counts["skills"]
                row.plan_count += self._counts["plans"]
                row.size_bytes = files.size_on_disk(self._root, row.id)
                if not row.source_text and self._plan_names:  # the last plan the session ran produced its run
                    source = services.plan_source(session, self._user_id, self._plan_names[-1])
                    if source is not None:
                        row.source_text, row.source_name = source[0], source[1][:200]


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else 0.0


def _numbers(values: object) -> list[float]:
    return [float(v) for v in values if isinstance(v, int | float)] if isinstance(values, list) else []


def _pose(value: object) -> robot_pb2.Pose2D:
    """A packed pose ({x_m, y_m, theta_rad}) as the robot's message."""
    if not isinstance(value, dict):
        return robot_pb2.Pose2D()
    return robot_pb2.Pose2D(x_m=float(value.get("x_m", value.get("x", 0.0)) or 0.0),
                            y_m=float(value.get("y_m", value.get("y", 0.0)) or 0.0),
                            theta_rad=float(value.get("theta_rad", value.get("theta", 0.0)) or 0.0))


def _json_object(text: str) -> dict[str, object]:
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _localization_from_packed(text: str) -> robot_pb2.LocalizationUpdate | None:
    """The hub's packed localization message (with the truth) as the robot's own message again."""
    try:
        message = json.loads(text)
    except ValueError:
        return None
    navigation = message.get("navigation") or {}
    return robot_pb2.LocalizationUpdate(
        sim_time_s=float(message.get("sim_time_s", 0.0)), active=bool(message.get("active")),
        converged=bool(message.get("converged")), estimate=_pose(message.get("estimate")),
        std_x_m=float(message.get("std_x_m") or 0.0), std_y_m=float(message.get("std_y_m") or 0.0),
        std_theta_rad=float(message.get("std_theta_rad") or 0.0), odometry=_pose(message.get("odometry")),
        ground_truth=_pose(message.get("ground_truth")),
        position_error_m=float(message.get("position_error_m") or 0.0),
        navigation_pose=_pose(navigation.get("pose")), navigation_source=str(navigation.get("source") or ""))


class RecordingKeeper:
    """The thread, in every process, whose elected instance opens, records, completes and sweeps recordings."""

    def __init__(self, app: Flask, sessions: Callable[[], Session], registry: RobotRegistry,
                 settings: RecordingSettings) -> None:
        self._app = weakref.ref(app)
        self._sessions, self._registry, self.settings = sessions, registry, settings
        self._election = ClusterElection(sessions.kw["bind"], RECORDINGS_LOCK)  # type: ignore[attr-defined]
        self._key = process_key()
        self._recorders: dict[int, SessionRecorder] = {}
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._swept_at = 0.0
        self._orphans_at = 0.0
        self._paused = False

    def pause(self, paused: bool) -> None:
        """While paused this process records nothing: its recorders let go at the next pass (their sessions stay
        open, and it goes on with them in new parts once resumed). For measuring what recording costs the live path
        in one run (benchmarks/recording_cost.py)."""
        self._paused = paused

    def start(self) -> None:
        """Starts the thread once."""
        with self._lock:
            if self._thread is None and not self._stop.is_set():
                self._thread = threading.Thread(target=self._keep_forever, name="recordings", daemon=True)
                self._thread.start()

    def stop(self) -> None:
        """Stops the thread and this process's recorders (their sessions stay open for another process)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        recorders = list(self._recorders.values())
        for recorder in recorders:
            recorder.abandon(wait=False)
        deadline = time.monotonic() + 3.0
        for recorder in recorders:  # their parts closed, all at once
            recorder.wait_closed(max(0.0, deadline - time.monotonic()))
        self._recorders.clear()
        self._election.resign()

    def recording_now(self) -> list[int]:
        """The ids this process records now."""
        return [rid for rid, recorder in self._recorders.items() if recorder.running]

    def _keep_forever(self) -> None:
        while not self._stop.wait(CHECK_S):
            if self._app() is None:
                return
            try:
                self.check()
            except Exception:  # noqa: BLE001 - one failed pass must not end the keeper
                log.exception("keeping the recordings failed")

    def check(self) -> None:
        """One pass: follow the sessions, record the open ones here, complete orphans, sweep now and then."""
        if self._paused or not self._election.leads():
            for recorder in self._recorders.values():
                recorder.abandon(wait=False)  # the next leader waits STALE_S before it goes on with them
            self._recorders.clear()
            return
        self._recorders = {rid: r for rid, r in self._recorders.items() if r.running}
        with self._sessions() as session, session.begin():  # one transaction a pass: it runs twice a second
            services.sync_sessions(session)
            stale = utc_now() - timedelta(seconds=STALE_S)
            for recording in services.open_recordings(session):
                if recording.id in self._recorders:
                    continue
                mine = recording.recorder_key == self._key
                if recording.recorder_key and not mine and recording.heard_at and as_utc(recording.heard_at) > stale:
                    continue  # another process records it (a leader a moment ago)
                link = self._registry.get(recording.robot_name)
                if link is None:
                    continue
                recording.recorder_key, recording.heard_at = self._key, utc_now()
                recorder = SessionRecorder(recording, link, self.settings.directory, self._sessions, self._key)
                self._recorders[recording.id] = recorder
            if time.monotonic() - self._orphans_at >= STALE_S:  # an orphan is STALE_S quiet before it counts
                self._orphans_at = time.monotonic()
                self._complete_orphans(session, stale)
        if time.monotonic() - self._swept_at >= SWEEP_S:
            self._swept_at = time.monotonic()
            self.sweep()

    def _complete_orphans(self, session: Session, stale: datetime) -> None:
        """Ended recordings whose recorder died before completing them: readable as they are (each part up to its
        last chunk); their size is taken from disk."""
        for recording in session.scalars(select(Recording).where(Recording.ended_at.is_not(None),
                                                                 Recording.status == "recording")):
            heard = as_utc(recording.heard_at) if recording.heard_at else as_utc(recording.started_at)
            if recording.id not in self._recorders and heard < stale:
                recording.status = "ready"
                recording.size_bytes = files.size_on_disk(self.settings.directory, recording.id)

    def sweep(self) -> list[int]:
        """Removes recordings past the retention or the disk limits, files no row names (a deleted account's),
        and old command rows; the ids removed."""
        root = self.settings.directory
        with self._sessions() as session, session.begin():
            doomed = services.removal_order(session, self.settings.max_total_bytes, self.settings.max_user_bytes,
                                            self.settings.retention_days)
            for recording_id in doomed:
                recording = session.get(Recording, recording_id)
                if recording is not None:
                    session.delete(recording)
            services.forget_old_commands(session, time.time())
            known = set(session.scalars(select(Recording.id)))
        for recording_id in doomed:
            files.remove_recording(root, recording_id)
        if root.is_dir():
            for folder in root.iterdir():
                if folder.is_dir() and folder.name.isdigit() and int(folder.name) not in known:
                    files.remove_recording(root, int(folder.name))
        return doomed

