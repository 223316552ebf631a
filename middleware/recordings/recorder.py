"""The recorder: one process of the cluster (elected like the access ticker) records every open session, a thread
per session reading the robot over streams of its own, writing MCAP parts to the shared directory.

Each second a session's thread closes its chunk (fsync), copies the commands other workers logged, notes goal
changes and tells the database it is alive. A session that ended is completed (footer, size, counts) by its
thread; a session whose recorder died (its process, or the election moved) is continued by the new leader in a
new part. The live path never waits for any of this: the recorder reads the robot on streams of its own, and the
command path only queues a note (command_log.py).
"""

from __future__ import annotations

import json
import logging
import threading
import time
import weakref
from collections.abc import Callable
from datetime import datetime, timedelta
from pathlib import Path

from flask import Flask
from sqlalchemy import select, update
from sqlalchemy.orm import Session

from middleware.assessment.recorder import process_key
from middleware.locking import ClusterElection, rows_matched
from middleware.models.accounts import as_utc, utc_now
from middleware.models.recordings import RecordedCommand, Recording
from middleware.recordings import channels, files, services
from middleware.recordings.settings import RecordingSettings
from middleware.robots.link import RobotLink
from middleware.robots.messages import unpack_camera_frame
from middleware.robots.registry import RobotRegistry
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
RATE_HZ = 10.0  # telemetry samples a second (odometry, truth, sonar, laser)
CAMERA_EVERY_S = 1.0  # a JPEG frame a second while someone watches the server camera...
CAMERA_EVERY_LONG_S = 5.0  # ...and one every 5 s after the session's first CAMERA_THIN_AFTER_S
CAMERA_THIN_AFTER_S = 600.0
CHECK_S = 0.5  # how often the keeper looks at the sessions
STALE_S = 5.0  # a recording not heard of for this long lost its recorder
SWEEP_S = 60.0  # retention and disk limits
RECORDINGS_LOCK = 0x7E1E_5EC0


def _ns(unix_s: float) -> int:
    return int(unix_s * 1e9)


class SessionRecorder:
    """Records one session until its row ends (then completes the file) or this process stops recording it."""

    def __init__(self, recording: Recording, link: RobotLink, root: Path, sessions: Callable[[], Session],
                 key: str) -> None:
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
        self._abandon = threading.Event()
        self._localizing = threading.Event()  # a localization goal runs: its estimate is worth a stream
        self._done = threading.Event()
        self._stream: object = None
        self._thread = threading.Thread(target=self._run, name=f"record-{recording.id}", daemon=True)
        self._localization = threading.Thread(target=self._record_localization, name=f"record-loc-{recording.id}",
                                              daemon=True)
        self._camera = threading.Thread(target=self._record_camera, name=f"record-cam-{recording.id}", daemon=True)
        self._thread.start()
        self._localization.start()
        self._camera.start()

    @property
    def running(self) -> bool:
        """Whether its thread still records."""
        return self._thread.is_alive()

    def abandon(self) -> None:
        """Stops recording without completing the session (another process goes on with it)."""
        self._abandon.set()
        self._cancel_stream()
        self._thread.join(timeout=3)

    def _cancel_stream(self) -> None:
        cancel = getattr(self._stream, "cancel", None)
        if cancel is not None:
            cancel()

    def _run(self) -> None:
        ended = False
        try:
            self._write_context()
            self._stream = self._link.stream_telemetry(RATE_HZ)
            last_second = time.monotonic()
            for telemetry in self._stream:
                self._write_telemetry(telemetry)
                if time.monotonic() - last_second >= files.FLUSH_S:
                    last_second = time.monotonic()
                    ended = not self._each_second()
                    if ended or self._abandon.is_set():
                        break
        except Exception as error:  # noqa: BLE001 - a broken stream: the keeper starts a new part if still open
            if not self._abandon.is_set():
                log.warning("recording %s on %s stopped: %s", self.recording_id, self._link.name, error)
        finally:
            self._done.set()
            self._cancel_stream()
            if ended:
                self._complete()
            else:
                self._writer.close()

    def _write_context(self) -> None:
        now_ns = time.time_ns()
        self._writer.write(channels.ROBOT_INFO, self._link.info(), now_ns)
        try:
            self._writer.write(channels.SCENE, self._link.scene(max_age_s=60.0), now_ns)
        except Exception as error:  # noqa: BLE001 - a robot with no scene: the replay draws the map alone
            log.info("recording %s: no scene (%s)", self.recording_id, error)

    def _write_telemetry(self, telemetry: robot_pb2.Telemetry) -> None:
        at = _ns(telemetry.capture_unix_s or time.time())
        self._writer.write(channels.ODOMETRY, telemetry.odometry, at)
        self._writer.write(channels.GROUND_TRUTH, telemetry.ground_truth, at)
        self._writer.write(channels.SONAR, telemetry.sonar, at)
        self._writer.write(channels.LASER, telemetry.laser, at)

    def _record_localization(self) -> None:
        """The localization estimate from the robot's fan-out hub (the live path's own stream, shared), only while
        a localization goal runs or someone in this process watches it anyway: subscribing would otherwise start
        the hub's pump (particles packed five times a second) on the live path's loop for nothing."""
        hub = self._link.localization
        subscription = None
        try:
            while not self._done.is_set():
                wanted = self._localizing.is_set() or hub.viewer_count - (1 if subscription is not None else 0) > 0
                if not wanted:
                    if subscription is not None:
                        subscription.close()
                        subscription = None
                    self._done.wait(0.5)
                    continue
                if subscription is None:
                    subscription = hub.subscribe()
                packed = subscription.next_message(timeout_s=0.5)
                if packed is None:
                    continue
                update_message = _localization_from_packed(packed[0])
                if update_message is not None and update_message.active:
                    self._writer.write(channels.LOCALIZATION, update_message, time.time_ns())
        except Exception as error:  # noqa: BLE001 - the hub closed: the telemetry goes on
            log.info("recording %s: localization stopped (%s)", self.recording_id, error)
        finally:
            if subscription is not None:
                subscription.close()

    def _record_camera(self) -> None:
        """JPEG frames, thinned, only while someone else in this process watches the server camera (a view drawn
        in the browser needs none: the replay redraws it from the scene and the poses)."""
        subscription = None
        started, last_capture = time.monotonic(), 0.0
        try:
            while not self._done.wait(0.2):
                hub = self._link.camera
                if hub.viewer_count - (1 if subscription is not None else 0) <= 0:
                    if subscription is not None:
                        subscription.close()
                        subscription = None
                    continue
                if subscription is None:
                    subscription = hub.subscribe()
                every = CAMERA_EVERY_S if time.monotonic() - started < CAMERA_THIN_AFTER_S else CAMERA_EVERY_LONG_S
                if time.time() - last_capture < every:
                    continue
                packed = subscription.next_message(timeout_s=0.5)
                if packed is None:
                    continue
                header, jpeg = unpack_camera_frame(packed)
                capture = float(header.get("capture_unix_s") or time.time())  # type: ignore[arg-type]
                if capture - last_capture < every:
                    continue  # thinned by the frames' own capture times
                frame = robot_pb2.CameraFrame(
                    frame_sequence=int(header.get("frame_sequence") or 0),  # type: ignore[call-overload]
                    capture_unix_s=capture, width_px=int(header.get("width_px") or 0),  # type: ignore[call-overload]
                    height_px=int(header.get("height_px") or 0), jpeg=jpeg)  # type: ignore[call-overload]
                self._writer.write(channels.CAMERA, frame, _ns(capture))
                last_capture = capture
        except Exception as error:  # noqa: BLE001 - the hub closed: the telemetry goes on
            log.info("recording %s: camera frames stopped (%s)", self.recording_id, error)
        finally:
            if subscription is not None:
                subscription.close()

    def _each_second(self) -> bool:
        """Copies new commands, notes goal changes, flushes, heartbeats; False once the session ended."""
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

    def _copy_commands(self, until_unix_s: float | None) -> None:
        with self._sessions() as session:
            query = (select(RecordedCommand).where(RecordedCommand.robot_name == self._link.name,
                                                   RecordedCommand.id > self._command_cursor,
                                                   RecordedCommand.sent_unix_s >= self._started_unix_s - 0.5)
                     .order_by(RecordedCommand.id))
            if until_unix_s is not None:
                query = query.where(RecordedCommand.sent_unix_s <= until_unix_s)
            rows = list(session.scalars(query))
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
        if any("localization" in goal.skill and goal.status in running for goal in goals):
            self._localizing.set()
        else:
            self._localizing.clear()
        if self._goals is None:
            # The robot lists the goals of whoever used it before, ended: they are not this session's (nor its
            # person's to read); only the ones running now, and every later change, are recorded.
            self._goals = {goal.goal_id: goal.status for goal in goals if goal.status not in running}
        for goal in goals:
            if self._goals.get(goal.goal_id) != goal.status:
                self._goals[goal.goal_id] = goal.status
                self._writer.write(channels.GOALS, goal, time.time_ns())

    def _complete(self) -> None:
        """The session ended: the commands up to its end, the footer, the size and the counts."""
        with self._sessions() as session:
            row = session.get(Recording, self.recording_id)
            ended_unix_s = as_utc(row.ended_at).timestamp() if row is not None and row.ended_at else time.time()
        time.sleep(0.4)  # the other workers' command logs write every 0.25 s
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

    def pose(value: object) -> robot_pb2.Pose2D:
        if not isinstance(value, dict):
            return robot_pb2.Pose2D()
        return robot_pb2.Pose2D(x_m=float(value.get("x_m", value.get("x", 0.0)) or 0.0),
                                y_m=float(value.get("y_m", value.get("y", 0.0)) or 0.0),
                                theta_rad=float(value.get("theta_rad", value.get("theta", 0.0)) or 0.0))

    navigation = message.get("navigation") or {}
    return robot_pb2.LocalizationUpdate(
        sim_time_s=float(message.get("sim_time_s", 0.0)), active=bool(message.get("active")),
        converged=bool(message.get("converged")), estimate=pose(message.get("estimate")),
        std_x_m=float(message.get("std_x_m") or 0.0), std_y_m=float(message.get("std_y_m") or 0.0),
        std_theta_rad=float(message.get("std_theta_rad") or 0.0), odometry=pose(message.get("odometry")),
        ground_truth=pose(message.get("ground_truth")),
        position_error_m=float(message.get("position_error_m") or 0.0),
        navigation_pose=pose(navigation.get("pose")), navigation_source=str(navigation.get("source") or ""))


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
        for recorder in list(self._recorders.values()):
            recorder.abandon()
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
        if not self._election.leads():
            for recorder in self._recorders.values():
                recorder.abandon()
            self._recorders.clear()
            return
        with self._sessions() as session, session.begin():
            services.sync_sessions(session)
        self._recorders = {rid: r for rid, r in self._recorders.items() if r.running}
        with self._sessions() as session, session.begin():
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

