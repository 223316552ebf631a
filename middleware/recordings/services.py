"""Which sessions are recorded and who may see them.

A session is one person controlling one robot: a lab robot's turn (robot_control), a practice robot's life (its
owner), or a session started by a call of start_recording() (an exercise run). Its kind says what it was for (an
attempt, a trial, a class session found open for that person and robot when it began). Everything here takes a
session and the acting user; the keeper and the routes own the units of work.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import ColumnElement, delete, func, select, update
from sqlalchemy.orm import Session

from middleware.courses.authority import taught_student_ids, teaches_student
from middleware.errors import ApiError
from middleware.models.access import RobotControl
from middleware.models.accounts import Role, User, as_utc, utc_now
from middleware.models.assessment import Attempt, Exam
from middleware.models.courses import CourseMembership
from middleware.models.experiment import Trial
from middleware.models.farm import PersonalRobotRecord
from middleware.models.plans import PlanVersion, StoredPlan
from middleware.models.recordings import RECORDING_KINDS, RecordedCommand, Recording

COMMANDS_KEPT_S = 24 * 3600  # command rows older than this are copied into their recording long ago


@dataclass(frozen=True)
class WantedSession:
    """A session the control tables say is going on now."""

    robot_name: str
    user_id: int
    started_at: datetime
    kind: str
    ref_id: int | None


class _Kinds:
    """What each (person, robot) is doing that gives its session a kind: an attempt in progress, then a trial
    assigned; read in two queries for every session at once (the elected keeper asks every second)."""

    def __init__(self, session: Session) -> None:
        self._attempts = self._first_ids(session, Attempt.id, Attempt.user_id, Attempt.robot_name,
                                         Attempt.status == "in_progress")
        self._trials = self._first_ids(session, Trial.id, Trial.user_id, Trial.robot_name, Trial.status == "assigned")

    @staticmethod
    def _first_ids(session: Session, id_column: Any, user_column: Any, robot_column: Any,
                   condition: ColumnElement[bool]) -> dict[tuple[int, str], int]:
        rows = session.execute(select(user_column, robot_column, func.min(id_column)).where(condition)
                               .group_by(user_column, robot_column))
        return {(user_id, robot_name): first for user_id, robot_name, first in rows if robot_name is not None}

    def of(self, user_id: int, robot_name: str) -> tuple[str, int | None]:
        attempt_id = self._attempts.get((user_id, robot_name))
        if attempt_id is not None:
            return "test_attempt", attempt_id
        trial_id = self._trials.get((user_id, robot_name))
        if trial_id is not None:
            return "experiment_trial", trial_id
        return "turn", None


def wanted_sessions(session: Session) -> dict[str, WantedSession]:
    """The controlled sessions going on now, by robot, from the tables every worker shares."""
    wanted: dict[str, WantedSession] = {}
    kinds = _Kinds(session)
    for control in session.scalars(select(RobotControl).where(RobotControl.controller_id.is_not(None))):
        assert control.controller_id is not None
        kind, ref_id = kinds.of(control.controller_id, control.robot_name)
        started = as_utc(control.turn_started_at or control.updated_at)
        wanted[control.robot_name] = WantedSession(control.robot_name, control.controller_id, started, kind, ref_id)
    for robot in session.scalars(select(PersonalRobotRecord).where(PersonalRobotRecord.address != "")):
        kind, ref_id = ("class_session", robot.class_session_id) if robot.class_session_id else ("practice", None)
        attempt_kind, attempt_ref = kinds.of(robot.owner_id, robot.name)
        if attempt_kind != "turn":
            kind, ref_id = attempt_kind, attempt_ref
        wanted[robot.name] = WantedSession(robot.name, robot.owner_id, as_utc(robot.started_at), kind, ref_id)
    return wanted


def open_recordings(session: Session) -> list[Recording]:
    """The recordings not yet ended."""
    return list(session.scalars(select(Recording).where(Recording.ended_at.is_(None)).order_by(Recording.id)))


def sync_sessions(session: Session, now: datetime | None = None) -> tuple[list[int], list[int]]:
    """Opens a recording for each session going on without one and ends those whose session ended (the turn passed
    or ended, the robot stopped); (opened ids, ended ids). Explicit recordings are ended by their caller only."""
    now = now or utc_now()
    wanted = wanted_sessions(session)
    opened, ended = [], []
    by_robot: dict[str, Recording] = {}
    for recording in open_recordings(session):
        want = wanted.get(recording.robot_name)
        if recording.explicit:
            by_robot[recording.robot_name] = recording
            continue
        same = want is not None and want.user_id == recording.user_id and abs(
            (want.started_at - as_utc(recording.started_at)).total_seconds()) < 1.0
        if same:
            assert want is not None
            if recording.kind == "turn" and want.kind != "turn":  # an attempt or trial began during the turn
                recording.kind, recording.ref_id = want.kind, want.ref_id
            by_robot[recording.robot_name] = recording
            continue
        recording.ended_at = now
        recording.end_reason = ("robot_stopped" if want is None and _personal(session, recording.robot_name)
                                else "turn_ended" if want is None or want.user_id == recording.user_id
                                else "handed_over")
        ended.append(recording.id)
    for robot_name, want in wanted.items():
        if robot_name not in by_robot:
            recording = Recording(user_id=want.user_id, robot_name=robot_name, kind=want.kind, ref_id=want.ref_id,
                                  explicit=False, started_at=want.started_at, status="recording")
            session.add(recording)
            session.flush()
            opened.append(recording.id)
    return opened, ended


def _personal(session: Session, robot_name: str) -> bool:
    return session.get(PersonalRobotRecord, robot_name) is not None or robot_name.startswith("practice-")


def start_recording(session: Session, user_id: int, robot_name: str, kind: str, ref_id: int | None = None,
                    source_text: str | None = None, source_name: str | None = None) -> Recording:
    """Starts recording a session of kind (an exercise run, a plan run) on the robot now; the elected recorder
    picks it up within a second. A turn recording open on that robot ends (end_reason 'superseded') and the
    control tables' session is not recorded again until this one ends. source_text is the code or plan that
    drives the run (exported beside the MCAP)."""
    if kind not in RECORDING_KINDS:
        raise ValueError(f"unknown recording kind {kind!r}")
    now = utc_now()
    session.execute(update(Recording).where(Recording.robot_name == robot_name, Recording.ended_at.is_(None))
                    .values(ended_at=now, end_reason="superseded"))
    recording = Recording(user_id=user_id, robot_name=robot_name[:64], kind=kind, ref_id=ref_id, explicit=True,
                          started_at=now, status="recording", source_text=source_text,
                          source_name=(source_name or "")[:200] or None)
    session.add(recording)
    session.flush()
    return recording


def stop_recording(session: Session, recording_id: int, reason: str = "finished") -> bool:
    """Ends the recording (its file is completed by the recorder within a second); False if it had ended."""
    return bool(session.execute(update(Recording).where(Recording.id == recording_id, Recording.ended_at.is_(None))
                                .values(ended_at=utc_now(), end_reason=reason[:32])).rowcount)  # type: ignore[attr-defined]


_TASK_FIELDS = ("kind", "x_m", "y_m", "x1_m", "y1_m", "x2_m", "y2_m", "distance_m")


def attempt_measurement(session: Session, recording: Recording) -> dict[str, object] | None:
    """For a test attempt's run: the task the rubric measured (its target or wall), the student's reported pose,
    and the grader's sentence and points, for the replay to draw; None for any other run."""
    if recording.kind != "test_attempt" or recording.ref_id is None:
        return None
    attempt = session.get(Attempt, recording.ref_id)
    exam = session.get(Exam, attempt.exam_id) if attempt is not None else None
    if attempt is None or exam is None or not exam.task:
        return None
    result = next((r for r in attempt.results or [] if r.get("item") == "task"), None)
    report = (attempt.answers or {}).get("report") if isinstance(attempt.answers, dict) else None
    return {"attempt_id": attempt.id, "task": {k: exam.task[k] for k in _TASK_FIELDS if k in exam.task},
            "report": report if isinstance(report, dict) else None,
            "feedback": result.get("feedback") if result else None,
            "points": result.get("points") if result else None, "max_points": result.get("max_points") if result
            else None}


def plan_source(session: Session, user_id: int, plan_name: str) -> tuple[str, str] | None:
    """The text of the plan a run sent under plan_name (the runner's own plan of that name, else a shared one),
    at its latest version, and a file name for it; None when no stored plan has that name."""
    plans = session.scalars(select(StoredPlan).where(StoredPlan.name == plan_name)
                            .order_by((StoredPlan.owner_id == user_id).desc(), StoredPlan.id.desc()).limit(1))
    plan = next(iter(plans), None)
    if plan is None:
        return None
    text = session.scalar(select(PlanVersion.text).where(PlanVersion.plan_id == plan.id,
                                                         PlanVersion.version == plan.latest_version))
    return (text, f"{plan.name}.plan.txt") if text is not None else None


def may_see_truth(actor: User) -> bool:
    """Whether actor's replay and exports carry the ground truth (tutors and admins; graders read it anyway)."""
    return actor.role in (Role.TUTOR, Role.ADMIN)


def visible_recording(session: Session, actor: User, recording_id: int) -> Recording:
    """The recording if actor may see it (theirs; a tutor: a student's of their courses; an admin: any), else 404
    (another's recording is answered like a missing one)."""
    recording = session.get(Recording, recording_id)
    if recording is None or not may_see(session, actor, recording):
        raise ApiError(404, "unknown_recording", gettext("There is no such recording."), "recording_id")
    return recording


def may_see(session: Session, actor: User, recording: Recording) -> bool:
    """The privacy rule (middleware/recordings/README.md)."""
    if recording.user_id == actor.id or actor.role == Role.ADMIN:
        return True
    owner = session.get(User, recording.user_id)
    return owner is not None and actor.role == Role.TUTOR and teaches_student(session, actor, owner)


def visible_recordings(session: Session, actor: User, limit: int = 200, offset: int = 0) -> list[Recording]:
    """The recordings actor may see, newest first."""
    query = select(Recording).order_by(Recording.started_at.desc(), Recording.id.desc())
    if actor.role == Role.STUDENT:
        query = query.where(Recording.user_id == actor.id)
    elif actor.role == Role.TUTOR:
        taught = taught_student_ids(actor)
        query = query.where((Recording.user_id == actor.id) | Recording.user_id.in_(taught))  # type: ignore[arg-type]
    return list(session.scalars(query.limit(limit).offset(offset)))


def recording_for(session: Session, actor: User, kind: str, ref_id: int) -> Recording | None:
    """The newest recording of kind for ref_id (an attempt's, an exercise run's) that actor may see."""
    candidates = session.scalars(select(Recording).where(Recording.kind == kind, Recording.ref_id == ref_id)
                                 .order_by(Recording.id.desc()).limit(5))
    return next((r for r in candidates if may_see(session, actor, r)), None)


def storage_by_user(session: Session) -> list[tuple[int, str, int, int]]:
    """(user id, username, recordings, bytes) per user, largest first (the admin page)."""
    rows = session.execute(select(Recording.user_id, User.username, func.count(Recording.id),
                                  func.coalesce(func.sum(Recording.size_bytes), 0))
                           .join(User, User.id == Recording.user_id).group_by(Recording.user_id, User.username)
                           .order_by(func.coalesce(func.sum(Recording.size_bytes), 0).desc()))
    return [(int(a), str(b), int(c), int(d)) for a, b, c, d in rows]


def removal_order(session: Session, max_total_bytes: int, max_user_bytes: int, retention_days: int,
                  now: datetime | None = None) -> list[int]:
    """The ended recordings to remove: past the retention; then, while a user is over their limit, their oldest;
    then, while the total is over its limit, the oldest of people in no course (their course ended) first, then
    the oldest of everyone."""
    now = now or utc_now()
    ended = list(session.scalars(select(Recording).where(Recording.ended_at.is_not(None))
                                 .order_by(Recording.started_at, Recording.id)))
    cutoff = now - timedelta(days=retention_days)
    doomed = [r.id for r in ended if as_utc(r.started_at) < cutoff]
    kept = [r for r in ended if r.id not in set(doomed)]
    per_user: dict[int, int] = {}
    for recording in session.scalars(select(Recording)):
        if recording.id not in set(doomed):
            per_user[recording.user_id] = per_user.get(recording.user_id, 0) + recording.size_bytes
    for recording in kept:
        if per_user.get(recording.user_id, 0) > max_user_bytes:
            per_user[recording.user_id] -= recording.size_bytes
            doomed.append(recording.id)
    kept = [r for r in kept if r.id not in set(doomed)]
    total = sum(per_user.values())
    enrolled = set(session.scalars(select(CourseMembership.user_id)))
    for recording in sorted(kept, key=lambda r: (r.user_id in enrolled, as_utc(r.started_at), r.id)):
        if total <= max_total_bytes:
            break
        total -= recording.size_bytes
        doomed.append(recording.id)
    return doomed


def forget_old_commands(session: Session, now_unix_s: float) -> None:
    """Removes command rows every recording has long copied."""
    session.execute(delete(RecordedCommand).where(RecordedCommand.sent_unix_s < now_unix_s - COMMANDS_KEPT_S))


def as_iso(moment: datetime | None) -> str | None:
    """A stored time as ISO 8601 UTC."""
    return as_utc(moment).astimezone(UTC).isoformat() if moment is not None else None
