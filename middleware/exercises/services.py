"""The exercises' rules: the catalogue, code versions, runs placed and graded by the server, and who sees what.

Services take the session and the acting user and flush; the request's unit of work commits. A run's start, its
time window and its grade are the server's: the robot is placed where the server chose (a hidden random start
for a submission), and the grade is computed from the robot's own pose log between the run's start and its end
(never later than its time limit), never from anything the browser sends."""

from __future__ import annotations

import json
import random
import secrets
from collections.abc import Callable
from datetime import datetime, timedelta
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware import i18n
from middleware.courses.authority import taught_course_ids, taught_student_ids, teaches_course, teaches_student
from middleware.errors import ApiError, Refused
from middleware.exercises import grading
from middleware.exercises.catalogue import BUILT_IN
from middleware.models import Course, CourseMembership, Role, User
from middleware.models.accounts import as_utc
from middleware.models.exercises import Exercise, ExerciseAssignment, ExerciseCode, ExerciseRun

RATE_HZ = 20
GRACE_S = 1.0  # the page's finish call may come a little after the time limit
NO_RECORD = i18n.N_("The robot could not give its record of the run (it restarted or stopped meanwhile), so it cannot "
                    "be graded. Run it again.")
# (robot name, since, until) -> the robot's trace [t_s, gx, gy, gth, ox, oy, oth], or None when it cannot tell
PoseLogReader = Callable[[str, datetime, datetime], list[list[float]] | None]
# (session, the course's test, the student's id, their new mark in points or None) in the unit of work that changed it
MarkListener = Callable[[Session, ExerciseAssignment, int, float | None], object]
_mark_listeners: list[MarkListener] = []


class ExerciseRefused(Refused):
    """A refusal of the exercises area."""


def ensure_catalogue(session: Session) -> None:
    """Adds the built-in exercises the database lacks (a second worker adding the same one at once is harmless)."""
    present = set(session.scalars(select(Exercise.slug)))
    for entry in BUILT_IN:
        if entry["slug"] in present:
            continue
        try:
            with session.begin_nested():
                session.add(_new_exercise(entry, None))
        except IntegrityError:
            continue


def _new_exercise(entry: dict[str, Any], author_id: int | None) -> Exercise:
    return Exercise(slug=entry["slug"], title=entry["title"], statement=entry["statement"],
                    template=entry["template"], scene=entry["scene"], rubric_json=json.dumps(entry["rubric"]),
                    start_json=json.dumps(entry["start"]),
                    random_starts_json=json.dumps(entry["random_starts"]), time_limit_s=entry["time_limit_s"],
                    created_by_id=author_id)


def catalogue(session: Session) -> list[Exercise]:
    """Every exercise, in the order they were added."""
    return list(session.scalars(select(Exercise).order_by(Exercise.id)))


def exercise_by_slug(session: Session, slug: str) -> Exercise:
    """The exercise (a built-in one is added to a database that lacks it), or a 404 naming slug."""
    exercise = session.scalar(select(Exercise).where(Exercise.slug == slug[:64]))
    if exercise is None and any(entry["slug"] == slug for entry in BUILT_IN):
        ensure_catalogue(session)
        exercise = session.scalar(select(Exercise).where(Exercise.slug == slug))
    if exercise is None:
        raise ApiError(404, "unknown_exercise", gettext("There is no such exercise."), "slug")
    return exercise


def may_edit_catalogue(actor: User) -> bool:
    """Tutors and admins extend the catalogue."""
    return actor.role in (Role.TUTOR, Role.ADMIN)


def _require_editor(actor: User) -> None:
    if not may_edit_catalogue(actor):
        raise ExerciseRefused(403, "forbidden", gettext("Only tutors and admins change the exercise catalogue."))


def add_exercise(session: Session, actor: User, fields: dict[str, Any]) -> Exercise:
    """A new exercise of the catalogue (409 when its slug is taken)."""
    _require_editor(actor)
    if session.scalar(select(Exercise.id).where(Exercise.slug == fields["slug"])) is not None:
        raise ExerciseRefused(409, "slug_taken", gettext("An exercise with that slug exists; choose another."), "slug")
    exercise = _new_exercise(fields, actor.id)
    session.add(exercise)
    session.flush()
    return exercise


def change_exercise(session: Session, actor: User, exercise: Exercise, fields: dict[str, Any], now: datetime) -> None:
    """Rewrites an exercise's definition (runs already graded keep their grades)."""
    _require_editor(actor)
    exercise.title, exercise.statement, exercise.template = fields["title"], fields["statement"], fields["template"]
    exercise.scene, exercise.time_limit_s = fields["scene"], fields["time_limit_s"]
    exercise.rubric_json, exercise.start_json = json.dumps(fields["rubric"]), json.dumps(fields["start"])
    exercise.random_starts_json, exercise.updated_at = json.dumps(fields["random_starts"]), now
    session.flush()


def exercise_dict(exercise: Exercise, full: bool = False) -> dict[str, Any]:
    """What a student reads of an exercise (never the hidden starts' region)."""
    answer: dict[str, Any] = {"slug": exercise.slug, "title": exercise.title, "scene": exercise.scene,
                              "time_limit_s": exercise.time_limit_s, "rate_hz": RATE_HZ}
    if full:
        answer.update(statement=exercise.statement, template=exercise.template,
                      rubric=json.loads(exercise.rubric_json), practice_start=json.loads(exercise.start_json))
    return answer


def save_code(session: Session, user: User, exercise: Exercise, text: str, now: datetime) -> ExerciseCode:
    """A new version of the user's code (the same text as their latest is not stored twice)."""
    latest = latest_code(session, user.id, exercise.id)
    if latest is not None and latest.code == text:
        return latest
    version = ExerciseCode(exercise_id=exercise.id, user_id=user.id, code=text, saved_at=now)
    session.add(version)
    session.flush()
    return version


def latest_code(session: Session, user_id: int, exercise_id: int) -> ExerciseCode | None:
    """The user's latest code version for the exercise."""
    return session.scalar(select(ExerciseCode).where(ExerciseCode.user_id == user_id,
                                                     ExerciseCode.exercise_id == exercise_id)
                          .order_by(ExerciseCode.id.desc()).limit(1))


def draw_start(exercise: Exercise, mode: str, seed: int) -> list[float]:
    """Where the robot starts: the exercise's practice start, or for a submission a start drawn from its hidden
    region with seed (the practice start when it has none)."""
    region = json.loads(exercise.random_starts_json)
    if mode != "submission" or not region:
        return [float(v) for v in json.loads(exercise.start_json)]
    draw = random.Random(seed)
    return [draw.uniform(*region["x_m"]), draw.uniform(*region["y_m"]), draw.uniform(*region["theta_rad"])]


def kidnaps(exercise: Exercise) -> bool:
    """Whether the exercise carries the robot to its start without telling it (odometry goes on from where the robot
    believed it was): the localize-after-a-kidnapping kind."""
    return bool(json.loads(exercise.rubric_json).get("kind") == "kidnapped")


def begin_run(session: Session, user: User, exercise: Exercise, code_version: ExerciseCode, mode: str,
              robot_name: str, robot_scene: str, place: Callable[[list[float]], None], now: Callable[[], datetime],
              read_log: PoseLogReader) -> ExerciseRun:
    """Places the user's robot at the run's start and opens the run from that moment; a run of theirs still open
    is graded first, up to now (a bad submission cannot be dropped by starting another)."""
    if robot_scene != exercise.scene:
        raise ExerciseRefused(409, "wrong_scene", gettext(
            "This exercise runs in the %(scene)s scene and your robot runs %(robot_scene)s; start a robot in that "
            "scene.", scene=repr(exercise.scene), robot_scene=repr(robot_scene)), "robot")
    for open_run in session.scalars(select(ExerciseRun).where(ExerciseRun.user_id == user.id,
                                                              ExerciseRun.status == "running")):
        finish_run(session, user, open_run, None, read_log, now())
    seed = secrets.randbelow(2**31)
    start = draw_start(exercise, mode, seed)
    place(start)
    run = ExerciseRun(exercise_id=exercise.id, user_id=user.id, code_id=code_version.id, robot_name=robot_name,
                      mode=mode, seed=seed, start_json=json.dumps([round(v, 4) for v in start]), started_at=now(),
                      status="running")
    session.add(run)
    session.flush()
    return run


def run_for(session: Session, viewer: User, run_id: int) -> ExerciseRun:
    """A run its owner, or a tutor teaching them, may read; 404 for anyone else."""
    run = session.get(ExerciseRun, run_id)
    if run is None or not (run.user_id == viewer.id or _teaches(session, viewer, run.user_id)):
        raise ApiError(404, "unknown_run", gettext("There is no such run."), "run_id")
    return run


def _teaches(session: Session, viewer: User, user_id: int) -> bool:
    target = session.get(User, user_id)
    return target is not None and teaches_student(session, viewer, target)


def finish_run(session: Session, user: User, run: ExerciseRun, report: dict[str, float] | None,
               read_log: PoseLogReader, now: datetime) -> ExerciseRun:
    """Grades the run from the robot's pose log between its start and now (at most its time limit)."""
    if run.user_id != user.id:
        raise ApiError(404, "unknown_run", gettext("There is no such run."), "run_id")
    if run.status != "running":
        return run
    exercise = session.get(Exercise, run.exercise_id)
    assert exercise is not None
    started = as_utc(run.started_at)
    ended = min(now, started + timedelta(seconds=exercise.time_limit_s + GRACE_S))
    trace = read_log(run.robot_name, started, ended)
    run.ended_at, run.report_json = ended, json.dumps(report)
    if trace is None:
        run.status, run.fraction = "failed", None
        run.feedback = NO_RECORD  # stored in English, said in the reader's language by run_dict
        session.flush()
        return run
    result = grading.grade(json.loads(exercise.rubric_json), trace, report)
    tests = _tests_of_student(session, run.user_id, run.exercise_id) if run.mode == "submission" else []
    before = {test.id: test_grade(session, run.user_id, test) for test in tests}
    run.status, run.fraction, run.feedback = "graded", result.fraction, result.feedback
    run.measurements_json = json.dumps(result.measurements_dict())
    run.trace_json = json.dumps([[s[0], s[1], s[2]] for s in trace])
    session.flush()
    for test in tests:
        _tell_if_changed(session, test, run.user_id, before[test.id])
    return run


def finish_if_overdue(session: Session, run: ExerciseRun, read_log: PoseLogReader, now: datetime) -> None:
    """Grades a run whose page never finished it (a closed tab) once its time limit has passed."""
    exercise = session.get(Exercise, run.exercise_id)
    if run.status == "running" and exercise is not None and \
            now >= as_utc(run.started_at) + timedelta(seconds=exercise.time_limit_s + GRACE_S):
        owner = session.get(User, run.user_id)
        if owner is not None:
            finish_run(session, owner, run, None, read_log, now)


def shown_feedback(run: ExerciseRun) -> tuple[str, list[dict[str, Any]]]:
    """The run's feedback and measurements in the reader's language: they are stored in English; a graded run's
    sentence is said again from its measurements, other feedback by the catalogue (as stored when it has it not)."""
    measurements = json.loads(run.measurements_json)
    if i18n.current_language() == i18n.LANGUAGES[0]:
        return run.feedback, measurements
    feedback = (grading.feedback_sentence(run.fraction, measurements)
                if run.status == "graded" and run.fraction is not None and measurements
                else str(gettext(run.feedback)) if run.feedback else run.feedback)
    return feedback, [{**m, "name": str(gettext(m["name"]))} for m in measurements]


def run_dict(run: ExerciseRun, with_trace: bool = False) -> dict[str, Any]:
    """A run as the pages show it: the start only once it is over (a submission's start is hidden until then)."""
    over = run.status != "running"
    feedback, measurements = shown_feedback(run)
    answer: dict[str, Any] = {
        "id": run.id, "mode": run.mode, "status": run.status, "robot_name": run.robot_name,
        "started_at": as_utc(run.started_at).isoformat(), "code_id": run.code_id,
        "ended_at": as_utc(run.ended_at).isoformat() if run.ended_at else None,
        "grade": run.fraction, "feedback": feedback, "measurements": measurements,
        "start": json.loads(run.start_json) if over or run.mode == "practice" else None,
    }
    if with_trace:
        answer["trace"] = json.loads(run.trace_json)
    return answer


def own_runs(session: Session, user: User, exercise: Exercise, limit: int = 20) -> list[ExerciseRun]:
    """The user's latest runs of the exercise."""
    return list(session.scalars(select(ExerciseRun).where(ExerciseRun.user_id == user.id,
                                                          ExerciseRun.exercise_id == exercise.id)
                                .order_by(ExerciseRun.id.desc()).limit(limit)))


def class_overview(session: Session, actor: User, exercise: Exercise) -> list[dict[str, Any]]:
    """For a tutor (their students) or an admin (everyone): each student's code versions, runs and best grade."""
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        raise ExerciseRefused(403, "forbidden", gettext("Only tutors and admins see the class's work."))
    taught = taught_student_ids(actor)
    users_query = select(User).where(User.role == Role.STUDENT).order_by(User.username)
    if taught is not None:
        users_query = users_query.where(User.id.in_(taught))
    rows = []
    for student in session.scalars(users_query):
        versions = list(session.scalars(select(ExerciseCode).where(ExerciseCode.user_id == student.id,
                                                                   ExerciseCode.exercise_id == exercise.id)
                                        .order_by(ExerciseCode.id)))
        runs = own_runs(session, student, exercise, limit=200)
        if not versions and not runs:
            continue
        graded = [r.fraction for r in runs if r.mode == "submission" and r.fraction is not None]
        rows.append({"user_id": student.id, "username": student.username,
                     "best_submission": max(graded) if graded else None,
                     "tests": tests_for(session, student, exercise),
                     "codes": [{"id": v.id, "saved_at": as_utc(v.saved_at).isoformat(), "code": v.code}
                               for v in versions],
                     "runs": [run_dict(r) for r in runs]})
    return rows


def attach_to_course(session: Session, actor: User, course_id: int, exercise: Exercise, deadline: datetime,
                     points: float) -> ExerciseAssignment:
    """Attaches the exercise to the course as a test (again: a new deadline and points), for its tutors."""
    if session.get(Course, course_id) is None:
        raise ApiError(404, "unknown_course", gettext("There is no such course."), "course_id")
    if not teaches_course(session, actor, course_id):
        raise ExerciseRefused(403, "forbidden", gettext("Only the course's tutors attach an exercise to it as a "
                                                         "test."))
    test = session.scalar(select(ExerciseAssignment).where(ExerciseAssignment.course_id == course_id,
                                                           ExerciseAssignment.exercise_id == exercise.id))
    if test is None:
        test = ExerciseAssignment(course_id=course_id, exercise_id=exercise.id, created_by_id=actor.id,
                                  deadline_at=deadline, points=points)
        session.add(test)
        session.flush()
        return test  # its line items in an LMS come later (placing it there), so no mark is waited for yet
    before = course_marks(session, test)
    test.deadline_at, test.points = deadline, points
    session.flush()
    for user_id in set(before) | set(course_marks(session, test)):
        _tell_if_changed(session, test, user_id, before.get(user_id))
    return test


def attachable_courses(session: Session, actor: User, exercise: Exercise) -> list[dict[str, Any]]:
    """The courses actor may attach the exercise to as a test (an admin: every course; a tutor: those they teach),
    each with the test it is already, if any (its deadline and points)."""
    if actor.role not in (Role.TUTOR, Role.ADMIN):
        return []
    query = select(Course).order_by(Course.title, Course.id)
    if actor.role != Role.ADMIN:
        query = query.where(Course.id.in_(taught_course_ids(actor)))
    tests = {test.course_id: test for test in session.scalars(select(ExerciseAssignment).where(
        ExerciseAssignment.exercise_id == exercise.id))}
    return [{"id": course.id, "title": course.title, "test": _test_terms(tests.get(course.id))}
            for course in session.scalars(query)]


def _test_terms(test: ExerciseAssignment | None) -> dict[str, Any] | None:
    return None if test is None else {"deadline_at": as_utc(test.deadline_at).isoformat(), "points": test.points,
                                      "leaderboard_open": test.leaderboard_open}


def best_submission(session: Session, user_id: int, test: ExerciseAssignment) -> ExerciseRun | None:
    """The submission the student's mark on the test comes from: their best graded one begun before the deadline,
    the first begun of equal ones (when they reached that mark)."""
    return session.scalar(select(ExerciseRun).where(
        ExerciseRun.user_id == user_id, ExerciseRun.exercise_id == test.exercise_id, ExerciseRun.mode == "submission",
        ExerciseRun.fraction.is_not(None), ExerciseRun.started_at <= test.deadline_at)
        .order_by(ExerciseRun.fraction.desc(), ExerciseRun.started_at, ExerciseRun.id).limit(1))


def mark_of(test: ExerciseAssignment, fraction: float) -> float:
    """A fraction of the test's points, as a mark (to the hundredth)."""
    return round(fraction * test.points, 2)


def test_grade(session: Session, user_id: int, test: ExerciseAssignment) -> float | None:
    """The student's mark on the test: the best graded submission begun before the deadline, in points."""
    best = best_submission(session, user_id, test)
    return None if best is None or best.fraction is None else mark_of(test, best.fraction)


def on_mark_change(listener: MarkListener) -> None:
    """Makes listener(session, test, user_id, mark) hear of every change of a student's mark on a course's test, in
    the unit of work that makes it (create_app hands it lti's passback; this area never imports lti)."""
    if listener not in _mark_listeners:
        _mark_listeners.append(listener)


def _tell_if_changed(session: Session, test: ExerciseAssignment, user_id: int, before: float | None) -> None:
    mark = test_grade(session, user_id, test)
    if mark != before:
        for listener in _mark_listeners:
            listener(session, test, user_id, mark)


def _tests_of_student(session: Session, user_id: int, exercise_id: int) -> list[ExerciseAssignment]:
    """The exercise's tests in the courses the user is a student of."""
    return list(session.scalars(select(ExerciseAssignment).join(
        CourseMembership, CourseMembership.course_id == ExerciseAssignment.course_id).where(
        CourseMembership.user_id == user_id, CourseMembership.role == "student",
        ExerciseAssignment.exercise_id == exercise_id).order_by(ExerciseAssignment.id)))


def course_marks(session: Session, test: ExerciseAssignment) -> dict[int, float]:
    """Each student of the test's course who has a mark on it: user id -> mark in points."""
    students = session.scalars(select(CourseMembership.user_id).where(
        CourseMembership.course_id == test.course_id, CourseMembership.role == "student"))
    marks = {user_id: test_grade(session, user_id, test) for user_id in students}
    return {user_id: mark for user_id, mark in marks.items() if mark is not None}


def tests_for(session: Session, user: User, exercise: Exercise) -> list[dict[str, Any]]:
    """The exercise's tests in the user's courses, with the user's mark so far."""
    rows = session.execute(select(ExerciseAssignment, Course).join(Course, Course.id == ExerciseAssignment.course_id)
                           .join(CourseMembership, CourseMembership.course_id == Course.id)
                           .where(CourseMembership.user_id == user.id, ExerciseAssignment.exercise_id == exercise.id)
                           .order_by(ExerciseAssignment.deadline_at))
    return [{"course_id": course.id, "course": course.title, "deadline_at": as_utc(test.deadline_at).isoformat(),
             "points": test.points, "mark": test_grade(session, user.id, test),
             "leaderboard_open": test.leaderboard_open} for test, course in rows]
