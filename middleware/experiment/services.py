"""Rules of the experiment: who may set a delay, how conditions are assigned, what a trial records, statistics.

Services take the acting user and a session and never read flask.request; the caller commits.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select

from middleware import events
from middleware.courses.authority import taught_course_ids, teaches_student
from middleware.errors import Refused
from middleware.experiment import protocol
from middleware.experiment.delay import parse_delay_s
from middleware.models import Course, CourseMembership, Role, User
from middleware.models.access import RobotControl
from middleware.models.accounts import utc_now
from middleware.models.experiment import TRIAL_OPEN, Participant, Trial, VideoDelay

COURSES = ("course-A", "course-B")
DELAYS_TOPIC = "delays"  # announced with the user's id when a delay in force may have changed
CONDITIONS: tuple[tuple[str, float, bool], ...] = tuple(
    (course, delay, feedback) for course in COURSES for delay, feedback in protocol.CONDITIONS_PER_COURSE
)
MAX_TRIAL_TIME_S = 3600.0
MAX_TRIAL_ERRORS = 1000


def _require_teacher(actor: User) -> None:
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        raise Refused(403, "forbidden", gettext("Only tutors and admins can do that."))


def get_video_delay(session, user_id: int) -> float:
    """The delay a tutor added to a user's video on every robot, 0 when none."""
    row = session.get(VideoDelay, user_id)
    return float(row.delay_s) if row is not None else 0.0


def _store_delay(session, user_id: int, delay_s: float, set_by_id: int) -> VideoDelay:
    row = session.get(VideoDelay, user_id)
    if row is None:
        row = VideoDelay(user_id=user_id, delay_s=delay_s, set_by_id=set_by_id, updated_at=utc_now())
        session.add(row)
    else:
        row.delay_s, row.set_by_id, row.updated_at = delay_s, set_by_id, utc_now()
    session.flush()
    events.announce(session, DELAYS_TOPIC, str(user_id))
    return row


def set_video_delay(session, actor: User, user_id: object, delay_s: object) -> VideoDelay:
    """A tutor sets the added video delay (0-7 s) of a student they teach, an admin anyone's, on every robot;
    a tutor's delay never holds commands (only a trial of a course whose protocol delays commands does)."""
    _require_teacher(actor)
    delay = parse_delay_s(delay_s)
    target = None if isinstance(user_id, bool) or not isinstance(user_id, int) else session.get(User, user_id)
    if target is None:
        raise Refused(404, "unknown_user", gettext("There is no such account."), "user_id")
    if not teaches_student(session, actor, target):
        raise Refused(403, "forbidden", gettext("You can set the delay only of students in the courses you teach."),
                      "user_id")
    return _store_delay(session, target.id, delay, actor.id)


def current_trial(session, student: User) -> Trial | None:
    """The student's trial in progress (assigned, not yet finished), if any."""
    return session.scalar(select(Trial).where(Trial.user_id == student.id, Trial.status == TRIAL_OPEN)
                          .order_by(Trial.id.desc()).limit(1))


def last_finished_trial(session, student: User) -> Trial | None:
    """The student's most recently ended trial, recorded or given up, if any (the page says which)."""
    return session.scalar(select(Trial).where(Trial.user_id == student.id, Trial.status != TRIAL_OPEN)
                          .order_by(Trial.id.desc()).limit(1))


def student_courses(session, student: User) -> list[Course]:
    """The courses student is enrolled in as a student, by code (a trial counts for one of them)."""
    return list(session.scalars(select(Course).join(CourseMembership, CourseMembership.course_id == Course.id)
                                .where(CourseMembership.user_id == student.id, CourseMembership.role == "student")
                                .order_by(Course.code)))


def trial_course_id(session, student: User, course_id: object) -> int | None:
    """The course a new trial counts for: the one named (it must be the student's), else the student's only course;
    None for a student of no course. A student of several courses must name one."""
    mine = {course.id for course in student_courses(session, student)}
    if course_id is None and len(mine) <= 1:
        return next(iter(mine), None)
    if course_id is None:
        raise Refused(400, "invalid_field", gettext("Choose the course this trial counts for."), "course_id")
    if isinstance(course_id, bool) or not isinstance(course_id, int) or course_id not in mine:
        raise Refused(400, "invalid_field", gettext("Choose one of your courses."), "course_id")
    return course_id


def may_restart_run(session, student: User, robot_name: str) -> bool:
    """Whether the student's trial may end the run under way on the robot: nobody else is driving it (a trial
    begun or given up must not spoil another student's run)."""
    control = session.get(RobotControl, robot_name)
    return control is None or control.controller_id in (None, student.id)


def assign_trial(session, student: User, robot_name: str, robot_scene: str, course_id: object = None) -> Trial:
    """Begins the student's next trial on the robot's course, counted for their class course (see
    trial_course_id), once they have answered the participant questions and their learning period is over: the
    next condition of their counterbalanced order (protocol.next_condition); its delay is on their video of that
    robot while the trial is open (the delay book reads open trials), and on their commands too when the course's
    protocol says so."""
    existing = current_trial(session, student)
    if existing is not None:
        return existing
    if robot_scene not in COURSES:
        raise Refused(409, "not_a_course", gettext("The robot %(robot_name)s does not run a course scene.",
                                                   robot_name=robot_name), "robot_name")
    class_course_id = trial_course_id(session, student, course_id)
    settings = protocol.protocol_for(session, class_course_id)
    protocol.require_ready(session, student, settings)
    delay, feedback = protocol.next_condition(session, student, class_course_id, robot_scene)
    trial = Trial(user_id=student.id, course_id=class_course_id, robot_name=robot_name, course=robot_scene,
                  delay_s=delay, feedback=feedback, status=TRIAL_OPEN, errors=0,
                  commands_delayed=settings.delay_commands and delay > 0, created_at=utc_now())
    session.add(trial)
    session.flush()
    events.announce(session, DELAYS_TOPIC, str(student.id))
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
        raise Refused(400, "invalid_field", gettext("total_time_s must be from 0 to %(max_trial_time_s)s s.",
                                                    max_trial_time_s=format(MAX_TRIAL_TIME_S, 'g')), "total_time_s")
    if isinstance(errors, bool) or not isinstance(errors, int) or not 0 <= errors <= MAX_TRIAL_ERRORS:
        raise Refused(400, "invalid_field", gettext("errors must be a whole number from 0."), "errors")


def finish_trial(session, student: User, trial_id: int, result: RunResult) -> Trial:
    """Records a completed run (time and errors as the robot measured them); the trial's delay ends with it."""
    trial = session.get(Trial, trial_id)
    if trial is None or trial.user_id != student.id:
        raise Refused(404, "unknown_trial", gettext("There is no such trial of yours."), "trial_id")
    if trial.status != TRIAL_OPEN:
        raise Refused(409, "trial_finished", gettext("This trial is already finished."), "trial_id")
    _check_result(result)
    trial.status, trial.total_time_s, trial.errors = "completed", float(result.total_time_s), int(result.errors)
    trial.finished_at = utc_now()
    events.announce(session, DELAYS_TOPIC, str(student.id))
    return trial


def abandon_trial(session, student: User, trial_id: int) -> Trial:
    """Gives up a trial in progress (it is not counted); the trial's delay ends with it."""
    trial = session.get(Trial, trial_id)
    if trial is None or trial.user_id != student.id or trial.status != TRIAL_OPEN:
        raise Refused(404, "unknown_trial", gettext("There is no trial of yours in progress with that number."),
                                            "trial_id")
    trial.status, trial.finished_at = "abandoned", utc_now()
    events.announce(session, DELAYS_TOPIC, str(student.id))
    return trial


def class_trials(session, actor: User) -> list[tuple[Trial, str]]:
    """The completed trials that count for the courses actor teaches (every one for an admin), with their
    usernames: a student in two courses is read by each course's tutors for that course's trials only."""
    _require_teacher(actor)
    query = (select(Trial, User.username).join(User, User.id == Trial.user_id)
             .where(Trial.status == "completed").order_by(Trial.id))
    if actor.role != Role.ADMIN:
        query = query.where(Trial.course_id.in_(taught_course_ids(actor)))
    rows = session.execute(query)
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


@dataclass(frozen=True)
class Comparison:
    """What the thesis reports for a course at one delay: the time the preview saves (the mean without it minus
    the mean with it, as a share of the former) and each mean against the no-delay control's."""

    course: str
    delay_s: float
    preview_saves: float | None
    on_vs_control: float | None
    off_vs_control: float | None


def compare(stats: Sequence[GroupStats]) -> list[Comparison]:
    """Per course and added delay, from the conditions' means (None where a condition has no trial yet)."""
    means = {(g.course, g.delay_s, g.feedback): g.mean_time_s for g in stats}
    comparisons = []
    for course in COURSES:
        control = means.get((course, protocol.CONTROL_DELAY_S, False))
        for delay in sorted({d for d, _ in protocol.CONDITIONS_PER_COURSE if d > protocol.CONTROL_DELAY_S}):
            on, off = means.get((course, delay, True)), means.get((course, delay, False))
            if on is None and off is None:
                continue
            comparisons.append(Comparison(
                course, delay, (off - on) / off if on is not None and off else None,
                on / control if on is not None and control else None,
                off / control if off is not None and control else None))
    return comparisons


def _cell(value: object) -> str:
    text = "" if value is None else str(value)
    return "'" + text if text[:1] in ("=", "+", "-", "@") else text


PARTICIPANT_COLUMNS = ("age", "location", "games_experience", "robots_experience")


def results_csv(rows: Sequence[tuple[Trial, str]], details: Mapping[int, Participant] | None = None) -> str:
    """One line per completed trial; cells starting with = + - @ are quoted against CSV injection. details: the
    participants whose details may go out (consenting, of a course whose tutor enabled it); the columns are there
    only when some may."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    extra = PARTICIPANT_COLUMNS if details else ()
    writer.writerow(["trial_id", "username", "robot", "course", "delay_s", "feedback", "commands_delayed",
                     "total_time_s", "errors", "finished_at_utc", *extra])
    for trial, username in rows:
        person = details.get(trial.user_id) if details else None
        writer.writerow([_cell(v) for v in (
            trial.id, username, trial.robot_name, trial.course, trial.delay_s, "on" if trial.feedback else "off",
            "yes" if trial.commands_delayed else "no", round(trial.total_time_s or 0.0, 3), trial.errors,
            trial.finished_at.isoformat() if trial.finished_at else "",
            *(getattr(person, column) if person is not None else "" for column in extra))])
    return out.getvalue()


def exportable_details(session, rows: Sequence[tuple[Trial, str]]) -> dict[int, Participant]:
    """The details that may go into an export of rows: a consenting participant's, for trials of a course whose
    protocol enables it."""
    allowed = {trial.user_id for trial, _ in rows
               if trial.course_id is not None and protocol.protocol_for(session, trial.course_id).export_participants}
    if not allowed:
        return {}
    return {p.user_id: p for p in session.scalars(select(Participant).where(Participant.user_id.in_(allowed),
                                                                           Participant.consent.is_(True)))}
