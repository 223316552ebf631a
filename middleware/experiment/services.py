"""Rules of the experiment: who may set a delay, how conditions are assigned, what a trial records, statistics.

Services take the acting user and a session and never read flask.request; the caller commits.
"""

from __future__ import annotations

import csv
import io
import math
import random
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from sqlalchemy import select

from middleware.accounts.services import Refused
from middleware.lab.delay import parse_delay_s
from middleware.models import Role, User
from middleware.models.accounts import utc_now
from middleware.models.experiment import Trial, VideoDelay

COURSES = ("course-A", "course-B")
TRIAL_DELAYS_S = (1.0, 3.0)
CONDITIONS: tuple[tuple[str, float, bool], ...] = tuple(
    (course, delay, feedback) for course in COURSES for delay in TRIAL_DELAYS_S for feedback in (True, False)
)
MAX_TRIAL_TIME_S = 3600.0
MAX_TRIAL_ERRORS = 1000


def _require_teacher(actor: User) -> None:
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        raise Refused(403, "forbidden", "Only tutors and admins can do that.")


def get_video_delay(session, user_id: int) -> float:  # type: ignore[no-untyped-def]
    """The injected delay of a user, 0 when none."""
    row = session.get(VideoDelay, user_id)
    return float(row.delay_s) if row is not None else 0.0


def _store_delay(session, user_id: int, delay_s: float, set_by_id: int | None) -> VideoDelay:  # type: ignore[no-untyped-def]
    row = session.get(VideoDelay, user_id)
    if row is None:
        row = VideoDelay(user_id=user_id, delay_s=delay_s, set_by_id=set_by_id, updated_at=utc_now())
        session.add(row)
    else:
        row.delay_s, row.set_by_id, row.updated_at = delay_s, set_by_id, utc_now()
    session.flush()
    return row


def set_video_delay(session, actor: User, user_id: object, delay_s: object) -> VideoDelay:  # type: ignore[no-untyped-def]
    """A tutor or admin sets one user's added video delay (0-7 s); commands are never delayed."""
    _require_teacher(actor)
    delay = parse_delay_s(delay_s)
    if isinstance(user_id, bool) or not isinstance(user_id, int) or session.get(User, user_id) is None:
        raise Refused(404, "unknown_user", "There is no such account.", "user_id")
    return _store_delay(session, user_id, delay, actor.id)


def current_trial(session, student: User) -> Trial | None:  # type: ignore[no-untyped-def]
    """The student's trial in progress (assigned, not yet finished), if any."""
    return session.scalar(select(Trial).where(Trial.user_id == student.id, Trial.status == "assigned")
                          .order_by(Trial.id.desc()).limit(1))


def last_completed_trial(session, student: User) -> Trial | None:  # type: ignore[no-untyped-def]
    """The student's most recently recorded trial, if any."""
    return session.scalar(select(Trial).where(Trial.user_id == student.id, Trial.status == "completed")
                          .order_by(Trial.id.desc()).limit(1))


def choose_condition(done: Iterable[tuple[str, float, bool]], courses: Sequence[str],
                     rng: random.Random) -> tuple[str, float, bool]:
    """A random condition among the ones this student has run least (balanced), on the courses available."""
    candidates = [c for c in CONDITIONS if c[0] in courses]
    if not candidates:
        raise Refused(409, "no_course_robot", "No robot runs a course scene now. Ask your tutor to start one.",
                      "robot_name")
    counts = Counter(done)
    fewest = min(counts[c] for c in candidates)
    return rng.choice([c for c in candidates if counts[c] == fewest])


def assign_trial(session, student: User, robot_name: str, robot_scene: str,  # type: ignore[no-untyped-def]
                 rng: random.Random | None = None) -> Trial:
    """Assigns the student a random condition on the robot's course and applies its delay to their video."""
    existing = current_trial(session, student)
    if existing is not None:
        return existing
    if robot_scene not in COURSES:
        raise Refused(409, "not_a_course", f"The robot {robot_name} does not run a course scene.", "robot_name")
    done = [(t.course, t.delay_s, t.feedback) for t in session.scalars(
        select(Trial).where(Trial.user_id == student.id, Trial.status == "completed"))]
    course, delay, feedback = choose_condition(done, [robot_scene], rng or random.SystemRandom())
    trial = Trial(user_id=student.id, robot_name=robot_name, course=course, delay_s=delay, feedback=feedback,
                  status="assigned", errors=0, created_at=utc_now())
    session.add(trial)
    _store_delay(session, student.id, delay, None)
    session.flush()
    return trial


@dataclass(frozen=True)
class RunResult:
    """What the robot's course monitor measured for the run that ended."""

    total_time_s: float
    errors: int


def _check_result(result: RunResult) -> None:
    time_s, errors = result.total_time_s, result.errors
    if isinstance(time_s, bool) or not isinstance(time_s, int | float) or not math.isfinite(time_s) \
            or not 0 < time_s <= MAX_TRIAL_TIME_S:
        raise Refused(400, "invalid_field", f"total_time_s must be from 0 to {MAX_TRIAL_TIME_S:g} s.", "total_time_s")
    if isinstance(errors, bool) or not isinstance(errors, int) or not 0 <= errors <= MAX_TRIAL_ERRORS:
        raise Refused(400, "invalid_field", "errors must be a whole number from 0.", "errors")


def finish_trial(session, student: User, trial_id: int, result: RunResult) -> Trial:  # type: ignore[no-untyped-def]
    """Records a completed run (time and errors as the robot measured them) and removes the added delay."""
    trial = session.get(Trial, trial_id)
    if trial is None or trial.user_id != student.id:
        raise Refused(404, "unknown_trial", "There is no such trial of yours.", "trial_id")
    if trial.status != "assigned":
        raise Refused(409, "trial_finished", "This trial is already finished.", "trial_id")
    _check_result(result)
    trial.status, trial.total_time_s, trial.errors = "completed", float(result.total_time_s), int(result.errors)
    trial.finished_at = utc_now()
    _store_delay(session, student.id, 0.0, None)
    return trial


def abandon_trial(session, student: User, trial_id: int) -> Trial:  # type: ignore[no-untyped-def]
    """Gives up a trial in progress (it is not counted) and removes the added delay."""
    trial = session.get(Trial, trial_id)
    if trial is None or trial.user_id != student.id or trial.status != "assigned":
        raise Refused(404, "unknown_trial", "There is no trial of yours in progress with that number.", "trial_id")
    trial.status, trial.finished_at = "abandoned", utc_now()
    _store_delay(session, student.id, 0.0, None)
    return trial


def class_trials(session, actor: User) -> list[tuple[Trial, str]]:  # type: ignore[no-untyped-def]
    """Every completed trial with its student's username (tutors and admins)."""
    _require_teacher(actor)
    rows = session.execute(select(Trial, User.username).join(User, User.id == Trial.user_id)
                           .where(Trial.status == "completed").order_by(Trial.id))
    return [(trial, username) for trial, username in rows]


@dataclass(frozen=True)
class GroupStats:
    """Mean total time of one condition with its standard error (sample sd / sqrt(n); None for n < 2)."""

    course: str
    delay_s: float
    feedback: bool
    n: int
    mean_time_s: float
    standard_error_s: float | None
    mean_errors: float


def summarise(trials: Iterable[Trial]) -> list[GroupStats]:
    """Statistics per (course, delay, feedback), in a stable order."""
    groups: dict[tuple[str, float, bool], list[Trial]] = {}
    for trial in trials:
        if trial.status == "completed" and trial.total_time_s is not None:
            groups.setdefault((trial.course, trial.delay_s, trial.feedback), []).append(trial)
    stats = []
    for (course, delay, feedback), members in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][1], not kv[0][2])):
        times = [float(t.total_time_s) for t in members]  # type: ignore[arg-type]
        n = len(times)
        mean = sum(times) / n
        se = math.sqrt(sum((x - mean) ** 2 for x in times) / (n - 1)) / math.sqrt(n) if n > 1 else None
        stats.append(GroupStats(course, delay, feedback, n, mean, se, sum(t.errors for t in members) / n))
    return stats


def _cell(value: object) -> str:
    text = "" if value is None else str(value)
    return "'" + text if text[:1] in ("=", "+", "-", "@") else text


def results_csv(rows: Sequence[tuple[Trial, str]]) -> str:
    """One line per completed trial; cells starting with = + - @ are quoted against CSV injection."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    writer.writerow(["trial_id", "username", "robot", "course", "delay_s", "feedback", "total_time_s", "errors",
                     "finished_at_utc"])
    for trial, username in rows:
        writer.writerow([_cell(v) for v in (
            trial.id, username, trial.robot_name, trial.course, trial.delay_s, "on" if trial.feedback else "off",
            round(trial.total_time_s or 0.0, 3), trial.errors,
            trial.finished_at.isoformat() if trial.finished_at else "")])
    return out.getvalue()
