"""The recorder's bookkeeping, in the writer child (writer.py), never in the worker's interpreter: once a second the
worker hands its child a tick (recorder.py: the command notes it saw, each tapped session's second of messages, and
for the robots of open recordings whether the worker can reach them and how many of its consoles watch them) and
the child does the rest:

- writes the notes to the command log (`recorded_commands`) and each second to its session's part, with the commands
  and goal changes of that second (the goals asked of the robot here, over a unary call of the child's own);
- when elected (`locking.ClusterElection`), opens and ends recordings as the control tables say
  (`services.sync_sessions`), completes orphans and sweeps past the limits;
- claims, heartbeats and lets go of sessions in the database, so a recording is never owned by one process's memory:
  a worker whose consoles watch the robot records it (it taps the one telemetry stream it holds anyway); a robot
  nobody watches is recorded by the elected worker over a stream of its own, marked `<key>#solo`, which any worker
  that streams the robot takes over; a recorder not heard of for STALE_S is taken over by whoever can;
- completes a session that ended once the other workers' notes of its last second are in (COMMANDS_SETTLE_S).

It answers which sessions the worker should tap now (and whether a localization runs on each), and the robots of the
open recordings, which the worker reports on at its next tick.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from datetime import timedelta
from pathlib import Path
from typing import Any

import grpc
from sqlalchemy import Engine, Table, and_, or_, select, update
from sqlalchemy.orm import Session

from middleware.locking import ClusterElection
from middleware.models.accounts import as_utc, utc_now
from middleware.models.recordings import RecordedCommand, Recording
from middleware.recordings import channels, files, services
from middleware.recordings.conversion import CommandRow, Kept, Record, json_object, write_second
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

log = logging.getLogger(__name__)

STALE_S = 5.0  # a recording not heard of for this long lost its recorder
SWEEP_S = 60.0  # retention and disk limits
COMMANDS_SETTLE_S = 1.5  # at a session's end: the other workers hand their notes to their children once a second
GOALS_TIMEOUT_S = 0.5  # the robot's unary calls from here (a robot away costs a tick this much, then is skipped)
ROBOT_AWAY_S = 5.0  # how long a robot that did not answer is not asked again
SOLO_AFTER_S = 2.0  # a new session nobody here watches waits this long for a worker that watches it to claim it
RECORDINGS_LOCK = 0x7E1E_5EC0
SOLO = "#solo"  # a recorder key's mark: this recorder holds a stream of the robot for the recording alone
_COMMANDS: Table = RecordedCommand.__table__  # type: ignore[assignment]
_RECORDINGS: Table = Recording.__table__  # type: ignore[assignment]
_RUNNING = (robot_pb2.GOAL_STATUS_ACCEPTED, robot_pb2.GOAL_STATUS_EXECUTING)

Present = tuple[str | None, int]  # a robot this worker reaches: its address, how many of the worker's consoles watch it


@dataclass
class Settings:
    """What the worker tells its child once: where the files go, its key, the limits."""

    directory: Path
    key: str
    max_total_bytes: int
    max_user_bytes: int
    retention_days: int


@dataclass
class _Part:
    """A session this child records now: its part, and what was copied into it."""

    recording_id: int
    robot_name: str
    user_id: int
    started_unix_s: float
    writer: files.PartWriter
    key: str  # as claimed in the row: the process's key, or it with SOLO
    cursor: int = 0  # the last command id copied
    goals: dict[str, int] | None = None  # None until the first look: goals ended before are not this session's
    localizing: bool = False
    context_written: bool = False
    ending_at: float | None = None  # unix s: the session ended; finished once the last notes are in
    ended_unix_s: float = 0.0
    address: str | None = None
    goals_at: float = 0.0


class Keeping:
    """The child's side of the recorder: the open parts and the tick's database work."""

    def __init__(self, engine: Engine, settings: Settings) -> None:
        self.engine, self.settings = engine, settings
        self._election = ClusterElection(engine, RECORDINGS_LOCK)
        self.parts: dict[int, _Part] = {}
        self._robots: dict[str, robot_pb2_grpc.RobotStub] = {}
        self._channels: dict[str, grpc.Channel] = {}
        self._away: dict[str, float] = {}
        self._swept_at = 0.0
        self._orphans_at = 0.0
        self._first_seen: dict[int, float] = {}  # open recordings: when this child first saw each (monotonic)

    def tick(self, tick: dict[str, Any]) -> dict[str, Any]:
        """One tick of the worker's (see the module's docstring); the answer."""
        self._log_commands(tick.get("notes") or [])
        seconds: dict[int, list[Kept]] = tick.get("seconds") or {}
        present: dict[str, Present] = tick.get("present") or {}
        commands = self._new_commands(list(self.parts.values()))
        for recording_id, part in list(self.parts.items()):
            if part.robot_name in present:  # its address may have changed
                part.address = present[part.robot_name][0]
            self._write_second(part, seconds.get(recording_id, []), commands=commands.get(recording_id, []))
        if tick.get("paused") or tick.get("releasing"):  # this worker records nothing now: the others go on
            self._let_go_all()
            self._finish_ended()
            return {"record": {}, "ask": []}
        leads = self._election.leads()
        with Session(self.engine) as session, session.begin():
            if leads:
                services.sync_sessions(session)
                session.flush()  # the claims below are Core statements: they see what it ended
            open_rows = services.open_recordings(session)
            asked = sorted({row.robot_name for row in open_rows})
            self._heartbeat_and_claim(session, open_rows, present, leads)
            if leads and time.monotonic() - self._orphans_at >= STALE_S:
                self._orphans_at = time.monotonic()
                self._complete_orphans(session)
        self._finish_ended()
        if leads and time.monotonic() - self._swept_at >= SWEEP_S:
            self._swept_at = time.monotonic()
            self.sweep()
        return {"record": {rid: (p.robot_name, p.localizing) for rid, p in self.parts.items() if p.ending_at is None},
                "ask": asked}

    # The command log: the worker's notes, as rows.
    def _log_commands(self, rows: list[dict[str, object]]) -> None:
        if rows:  # one Core executemany: no ORM unit of work for rows nobody reads back here
            with self.engine.begin() as connection:
                connection.execute(_COMMANDS.insert(), rows)

    # A second of a session: its messages, the commands logged meanwhile, its goal changes; chunk closed, fsynced.
    def _write_second(self, part: _Part, kept: list[Kept], until_unix_s: float | None = None,
                      commands: list[CommandRow] | None = None) -> None:
        records: list[Record] = [] if part.context_written else self._context(part)
        if time.monotonic() - part.goals_at >= files.FLUSH_S or until_unix_s is not None:
            part.goals_at = time.monotonic()
            records += self._goal_changes(part)
        if commands is None:
            commands = self._new_commands([part], until_unix_s)[part.recording_id]
        write_second(part.writer, kept, records, commands)

    def _stub(self, part: _Part) -> robot_pb2_grpc.RobotStub | None:
        address = part.address
        if address is None or time.monotonic() - self._away.get(address, -ROBOT_AWAY_S) < ROBOT_AWAY_S:
            return None
        if address not in self._robots:
            self._channels[address] = grpc.insecure_channel(address)
            self._robots[address] = robot_pb2_grpc.RobotStub(self._channels[address])
        return self._robots[address]

    def _context(self, part: _Part) -> list[Record]:
        """The robot's description and its scene, once (the replay redraws the views from them)."""
        stub = self._stub(part)
        if stub is None:
            return []
        now_ns = time.time_ns()
        try:
            info = stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=GOALS_TIMEOUT_S)
        except grpc.RpcError as error:
            self._away[str(part.address)] = time.monotonic()
            log.info("recording %s: no robot description yet (%s)", part.recording_id, error.code())
            return []
        part.context_written = True
        records = [(channels.ROBOT_INFO, info.SerializeToString(), now_ns)]
        try:
            scene = stub.GetScene(robot_pb2.GetSceneRequest(known_version=""), timeout=GOALS_TIMEOUT_S * 4)
            records.append((channels.SCENE, scene.SerializeToString(), now_ns))
        except grpc.RpcError as error:  # a robot with no scene: the replay draws the map alone
            log.info("recording %s: no scene (%s)", part.recording_id, error.code())
        return records

    def _goal_changes(self, part: _Part) -> list[Record]:
        stub = self._stub(part)
        if stub is None:
            return []
        try:
            goals = list(stub.ListGoals(robot_pb2.ListGoalsRequest(), timeout=GOALS_TIMEOUT_S).goals)
        except grpc.RpcError:  # the robot busy or away for a moment: later
            self._away[str(part.address)] = time.monotonic()
            return []
        part.localizing = any("localization" in goal.skill and goal.status in _RUNNING for goal in goals)
        if part.goals is None:
            # The robot lists the goals of whoever used it before, ended: they are not this session's (nor its
            # person's to read); only the ones running now, and every later change, are recorded.
            part.goals = {goal.goal_id: goal.status for goal in goals if goal.status not in _RUNNING}
        changes: list[Record] = []
        for goal in goals:
            if part.goals.get(goal.goal_id) != goal.status:
                part.goals[goal.goal_id] = goal.status
                changes.append((channels.GOALS, goal.SerializeToString(), time.time_ns()))
        return changes

    def _new_commands(self, parts: list[_Part], until_unix_s: float | None = None) -> dict[int, list[CommandRow]]:
        """Each part's commands logged on its robot after its cursor (sent since its session began, and until its
        end), read for every part at once: a query a tick, not one per session (a class of 50 recorded sessions
        was 50 of the database's transactions a second)."""
        if not parts:
            return {}
        c = _COMMANDS.c
        query = (select(c.id, c.robot_name, c.sent_unix_s, c.user_id, c.sequence, c.source, c.action, c.detail,
                        c.accepted, c.outcome)
                 .where(or_(*(and_(c.robot_name == part.robot_name, c.id > part.cursor,
                                   c.sent_unix_s >= part.started_unix_s - 0.5) for part in parts)))
                 .order_by(c.id))
        if until_unix_s is not None:
            query = query.where(c.sent_unix_s <= until_unix_s)
        with self.engine.connect() as connection:
            found = connection.execute(query).all()
        by_robot: dict[str, list[Any]] = {}
        for row in found:
            by_robot.setdefault(row.robot_name, []).append(row)
        commands: dict[int, list[CommandRow]] = {}
        for part in parts:  # two sessions of one robot share its rows: each takes those past its own cursor
            rows = [row for row in by_robot.get(part.robot_name, ())
                    if row.id > part.cursor and row.sent_unix_s >= part.started_unix_s - 0.5]
            if rows:
                part.cursor = rows[-1].id
            commands[part.recording_id] = [_command_row(row) for row in rows]
        return commands

    # Claims: which process records which session, in the rows.
    def _heartbeat_and_claim(self, session: Session, open_rows: list[Recording], present: dict[str, Present],
                             leads: bool) -> None:
        key = self.settings.key
        mine = (key, key + SOLO)
        now = utc_now()
        stale = now - timedelta(seconds=STALE_S)
        by_id = {row.id: row for row in open_rows}
        self._first_seen = {rid: self._first_seen.get(rid, time.monotonic()) for rid in by_id}
        for recording_id, part in list(self.parts.items()):
            if part.ending_at is not None:
                continue
            watched = present.get(part.robot_name, (None, 0))[1] > 0
            claim = key if watched else key + SOLO
            if recording_id in by_id and session.execute(update(_RECORDINGS).where(  # not taken over meanwhile
                    _RECORDINGS.c.id == recording_id, _RECORDINGS.c.recorder_key.in_(mine),
                    _RECORDINGS.c.ended_at.is_(None)).values(recorder_key=claim, heard_at=now)).rowcount:  # type: ignore[attr-defined]
                part.key = claim
                continue
            ended = session.get(Recording, recording_id, populate_existing=True)
            if ended is None or ended.recorder_key not in mine:
                self._let_go(recording_id)  # deleted, or another process took it over
            else:
                part.ended_unix_s = as_utc(ended.ended_at).timestamp() if ended.ended_at else time.time()
                part.ending_at = part.ended_unix_s + COMMANDS_SETTLE_S
        for row in open_rows:
            if row.id in self.parts or row.robot_name not in present:
                continue
            watched = present[row.robot_name][1] > 0
            holder = row.recorder_key
            heard = as_utc(row.heard_at) if row.heard_at else None
            if holder in mine:
                pass  # this worker's before it paused or its child restarted: on with it at once
            elif holder is None or heard is None or heard <= stale:
                # Free. A worker whose consoles watch the robot takes it; the elected one takes it when no such
                # worker did within SOLO_AFTER_S of its start (or its recorder died), over a stream of its own.
                new = heard is None and time.monotonic() - self._first_seen[row.id] < SOLO_AFTER_S
                if not watched and (not leads or new):
                    continue
            elif not (watched and holder.endswith(SOLO)):
                continue  # recorded by a worker that is alive (and watches the robot, or no worker here does)
            claim = key if watched else key + SOLO
            taken = session.execute(update(_RECORDINGS).where(
                _RECORDINGS.c.id == row.id, _RECORDINGS.c.ended_at.is_(None),
                _RECORDINGS.c.recorder_key.is_(None) if holder is None else _RECORDINGS.c.recorder_key == holder)
                .values(recorder_key=claim, heard_at=now)).rowcount  # type: ignore[attr-defined]
            session.expire(row)
            if taken:
                self._open(row, claim, present[row.robot_name][0])

    def _open(self, row: Recording, claim: str, address: str | None) -> None:
        path = files.new_part_path(self.settings.directory, row.id, self.settings.key)
        metadata = {"recording_id": str(row.id), "robot": row.robot_name, "user_id": str(row.user_id),
                    "kind": row.kind, "started_at": as_utc(row.started_at).isoformat(), "recorder": self.settings.key}
        self.parts[row.id] = _Part(row.id, row.robot_name, row.user_id, as_utc(row.started_at).timestamp(),
                                   files.PartWriter(path, metadata), claim, address=address)

    def _let_go(self, recording_id: int) -> None:
        """Closes the part without a summary (another process goes on with the session, or it was deleted)."""
        part = self.parts.pop(recording_id)
        try:
            part.writer.close()
        except Exception:  # noqa: BLE001 - its chunks are on disk already: the part reads up to the last one
            log.exception("recording %s: closing its part failed", recording_id)

    def _let_go_all(self) -> None:
        for recording_id, part in list(self.parts.items()):
            if part.ending_at is None:
                self._let_go(recording_id)

    # A session that ended: its last commands, the footer, the counts.
    def _finish_ended(self) -> None:
        for recording_id, part in list(self.parts.items()):
            if part.ending_at is None or time.time() < part.ending_at:
                continue
            del self.parts[recording_id]
            try:
                self._write_second(part, [], until_unix_s=part.ended_unix_s + 0.05)
                part.writer.finish()
                self._complete(part)
            except Exception:  # noqa: BLE001 - an orphan now: the elected child completes it from disk
                log.exception("recording %s: completing it failed", recording_id)

    def _complete(self, part: _Part) -> None:
        """Status, size and counts, from the command log itself (whoever recorded which part of the session)."""
        c = _COMMANDS.c
        with Session(self.engine) as session, session.begin():
            row = session.get(Recording, part.recording_id)
            if row is None:
                return
            commands = session.execute(select(c.action, c.accepted, c.detail).where(
                c.robot_name == part.robot_name, c.sent_unix_s >= part.started_unix_s - 0.5,
                c.sent_unix_s <= part.ended_unix_s + 0.05).order_by(c.id)).all()
            counts = command_counts([(action, accepted, detail) for action, accepted, detail in commands])
            row.status = "ready"
            row.command_count, row.skill_count, row.plan_count = counts[0], counts[1], counts[2]
            row.size_bytes = files.size_on_disk(self.settings.directory, row.id)
            if not row.source_text and counts[3]:  # the last plan the session ran produced its run
                source = services.plan_source(session, part.user_id, counts[3])
                if source is not None:
                    row.source_text, row.source_name = source[0], source[1][:200]

    def _complete_orphans(self, session: Session) -> None:
        """Ended recordings whose recorder died before completing them: readable as they are (each part up to its
        last chunk); their size is taken from disk."""
        stale = utc_now() - timedelta(seconds=STALE_S)
        for recording in session.scalars(select(Recording).where(Recording.ended_at.is_not(None),
                                                                 Recording.status == "recording")):
            heard = as_utc(recording.heard_at) if recording.heard_at else as_utc(recording.started_at)
            if recording.id not in self.parts and heard < stale:
                recording.status = "ready"
                recording.size_bytes = files.size_on_disk(self.settings.directory, recording.id)

    def sweep(self) -> list[int]:
        """Removes recordings past the retention or the disk limits, files no row names (a deleted account's),
        and old command rows; the ids removed."""
        root, settings = self.settings.directory, self.settings
        with Session(self.engine) as session, session.begin():
            doomed = services.removal_order(session, settings.max_total_bytes, settings.max_user_bytes,
                                            settings.retention_days)
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

    def close(self) -> None:
        """The worker is gone: every part ends at its last chunk (another process goes on with its session)."""
        for recording_id in list(self.parts):
            self._let_go(recording_id)
        for channel in self._channels.values():
            channel.close()
        self._election.resign()


def command_counts(commands: list[tuple[str, bool, str]]) -> tuple[int, int, int, str]:
    """(commands, skills run, plans run, the last plan's name) of a session's logged (action, accepted, detail)."""
    skills = plans = 0
    last_plan = ""
    for action, accepted, detail_text in commands:
        if not accepted or action not in ("activate", "run_plan"):
            continue
        detail = json_object(detail_text)
        if action == "activate" and detail.get("skill") != "direct_control":
            skills += 1
        if action == "run_plan":
            plans += 1
            last_plan = str(detail.get("plan_name", ""))
    return len(commands), skills, plans, last_plan


def _command_row(row: Any) -> CommandRow:
    """A recorded_commands row as the command channel's record takes it."""
    return (row.sent_unix_s, row.user_id or 0, row.sequence, row.source, row.action, row.detail, row.accepted,
            row.outcome)
