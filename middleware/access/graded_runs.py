"""A graded run keeps a shared robot: the priority rule for experimental test attempts and experiment trials.

A student who controls a shared robot while their experimental test's attempt on it (or their delay trial on
it, or their programming exercise's submission on it) is open keeps control past the turn length until the run
ends, so a run is never cut off by the turn passing to the next student. It ranks like a booking (the round-robin
rule's priority): the controller keeps the robot, with no countdown, while others wait. It never takes the robot
from another student's turn: the run's holder waits for their turn like everyone. The hold lasts at most the
longest `graded_run_hold_min` of the student's courses from the run's start (a forgotten trial cannot keep the
robot all day).
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import datetime, timedelta

from sqlalchemy import func, or_, select
from sqlalchemy.orm import Session

from middleware.models import Course, CourseMembership, RobotControl
from middleware.models.accounts import as_utc
from middleware.models.assessment import Attempt, Exam
from middleware.models.courses import DEFAULT_GRADED_RUN_HOLD_MIN
from middleware.models.exercises import ExerciseRun
from middleware.models.experiment import TRIAL_OPEN, Trial

Priority = Callable[[Session, str, datetime], int | None]


def graded_run_started_at(session: Session, robot_name: str, user_id: int, now: datetime) -> datetime | None:
    """When user_id's open graded run on robot_name began (the latest, if several); None without one."""
    attempt = session.scalar(select(func.max(Attempt.started_at)).join(Exam, Exam.id == Attempt.exam_id).where(
        func.coalesce(Attempt.robot_name, Exam.robot_name) == robot_name, Attempt.user_id == user_id,
        Attempt.status == "in_progress",
        or_(Attempt.deadline_at.is_(None), Attempt.deadline_at > now)))
    trial = session.scalar(select(func.max(Trial.created_at)).where(
        Trial.robot_name == robot_name, Trial.user_id == user_id, Trial.status == TRIAL_OPEN))
    # A programming exercise's submission is graded too (the kidnapping's reported pose must not be read off the
    # truth the streams carry).
    submission = session.scalar(select(func.max(ExerciseRun.started_at)).where(
        ExerciseRun.robot_name == robot_name, ExerciseRun.user_id == user_id, ExerciseRun.mode == "submission",
        ExerciseRun.status == "running"))
    starts = [as_utc(moment) for moment in (attempt, trial, submission) if moment is not None]
    return max(starts) if starts else None


def open_graded_runs(session: Session, now: datetime) -> set[tuple[str, int]]:
    """(robot name, user id) of every graded run open now: what graded_run_started_at finds, for everyone at once."""
    attempts = session.execute(select(func.coalesce(Attempt.robot_name, Exam.robot_name), Attempt.user_id).join(
        Exam, Exam.id == Attempt.exam_id).where(Attempt.status == "in_progress",
                                                or_(Attempt.deadline_at.is_(None), Attempt.deadline_at > now))).all()
    trials = session.execute(select(Trial.robot_name, Trial.user_id).where(Trial.status == TRIAL_OPEN)).all()
    submissions = session.execute(select(ExerciseRun.robot_name, ExerciseRun.user_id).where(
        ExerciseRun.mode == "submission", ExerciseRun.status == "running")).all()
    return {(robot, user_id) for robot, user_id in [*attempts, *trials, *submissions] if robot}


def robots_in_graded_runs(session: Session, now: datetime) -> set[str]:
    """Every robot with a graded run open now (graded_run_holder may name a holder of these only)."""
    return {robot_name for robot_name, _user_id in open_graded_runs(session, now)}


def graded_run_hold_s(session: Session, user_id: int) -> float:
    """The longest a graded run of user_id keeps a shared robot: the longest of their courses' settings."""
    longest = session.scalar(select(func.max(Course.graded_run_hold_min))
                             .join(CourseMembership, CourseMembership.course_id == Course.id)
                             .where(CourseMembership.user_id == user_id))
    return float(longest or DEFAULT_GRADED_RUN_HOLD_MIN) * 60


def graded_run_holder(session: Session, robot_name: str, now: datetime) -> int | None:
    """The robot's controller when their graded run on it is open and within its hold; None otherwise."""
    control = session.get(RobotControl, robot_name)  # the caller's locked row, from memory
    controller_id = control.controller_id if control is not None else None
    if controller_id is None:
        return None
    started = graded_run_started_at(session, robot_name, controller_id, now)
    if started is None or now - started > timedelta(seconds=graded_run_hold_s(session, controller_id)):
        return None
    return controller_id


def with_graded_run_priority(fallback: Priority) -> Priority:
    """A priority rule where an open graded run keeps its controller's robot, then fallback (bookings, classes).

    fallback is asked first every time, so its own bookkeeping (a no-show booking released) goes on."""

    def priority(session: Session, robot_name: str, now: datetime) -> int | None:
        booked = fallback(session, robot_name, now)
        holder = graded_run_holder(session, robot_name, now)
        return booked if holder is None else holder

    return priority
