"""A course's leaderboard of an exercise attached to it as a test: its students ranked by their mark on the test.

The mark is the test's own (services.best_submission: the best graded submission begun before the deadline); equal
marks are ranked by who began the submission that earned it first. Students with no mark are not ranked (they are
counted, never named). The course's tutors (and admins) always read it and open or close it; the course's students
read it only while it is open; anyone else is refused."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import ApiError
from middleware.exercises.services import ExerciseRefused, best_submission, mark_of
from middleware.models import Course, CourseMembership, User
from middleware.models.accounts import as_utc
from middleware.models.exercises import Exercise, ExerciseAssignment


@dataclass(frozen=True)
class Standing:
    """One ranked student: their place, their mark (in points and as a fraction) and when they reached it."""

    rank: int
    user_id: int
    username: str
    mark: float
    fraction: float
    reached_at: datetime


def course_test(session: Session, course_id: int, exercise: Exercise) -> tuple[Course, ExerciseAssignment]:
    """The course and the exercise's test in it; a 404 naming the field when either is missing."""
    course = session.get(Course, course_id)
    if course is None:
        raise ApiError(404, "unknown_course", gettext("There is no such course."), "course_id")
    test = session.scalar(select(ExerciseAssignment).where(ExerciseAssignment.course_id == course_id,
                                                           ExerciseAssignment.exercise_id == exercise.id))
    if test is None:
        raise ApiError(404, "not_a_test", gettext("This exercise is not a test of that course, so it has no "
                                                  "leaderboard there."), "slug")
    return course, test


def require_member(session: Session, viewer: User, test: ExerciseAssignment) -> bool:
    """True for the course's tutors (and admins), False for its students; anyone else is refused."""
    if teaches_course(session, viewer, test.course_id):
        return True
    if not _is_student_of(session, viewer.id, test.course_id):
        raise ExerciseRefused(403, "not_in_course", gettext("This leaderboard is for the members of another "
                                                             "course."), "course_id")
    return False


def require_reader(session: Session, viewer: User, test: ExerciseAssignment) -> None:
    """Lets the course's tutors (and admins) through, and its students while the leaderboard is open."""
    if not require_member(session, viewer, test) and not test.leaderboard_open:
        raise ExerciseRefused(403, "leaderboard_closed", gettext(
            "Your tutor has not opened this leaderboard; your own mark is on the exercise's page."), "slug")


def _is_student_of(session: Session, user_id: int, course_id: int) -> bool:
    return session.scalar(select(CourseMembership.id).where(
        CourseMembership.course_id == course_id, CourseMembership.user_id == user_id,
        CourseMembership.role == "student")) is not None


def standings(session: Session, test: ExerciseAssignment) -> tuple[list[Standing], int]:
    """The course's students with a mark, best first (equal marks: the one reached first), and how many have none."""
    students = session.execute(select(User.id, User.username).join(
        CourseMembership, CourseMembership.user_id == User.id).where(
        CourseMembership.course_id == test.course_id, CourseMembership.role == "student"))
    marked: list[tuple[float, datetime, str, int, float]] = []
    unranked = 0
    for user_id, username in students:
        best = best_submission(session, user_id, test)
        if best is None or best.fraction is None:
            unranked += 1
            continue
        marked.append((mark_of(test, best.fraction), as_utc(best.started_at), username, user_id, best.fraction))
    marked.sort(key=lambda row: (-row[0], row[1], row[2]))
    ranked = [Standing(place, user_id, username, mark, fraction, reached_at)
              for place, (mark, reached_at, username, user_id, fraction) in enumerate(marked, start=1)]
    return ranked, unranked


def leaderboard(session: Session, viewer: User, course_id: int, exercise: Exercise) -> dict[str, Any]:
    """The leaderboard as the page shows it to viewer (their own row marked), once require_reader lets them in."""
    course, test = course_test(session, course_id, exercise)
    require_reader(session, viewer, test)
    ranked, unranked = standings(session, test)
    return {"course": {"id": course.id, "title": course.title}, "slug": exercise.slug,
            "deadline_at": as_utc(test.deadline_at).isoformat(), "points": test.points,
            "open": test.leaderboard_open, "may_open": teaches_course(session, viewer, course.id),
            "standings": [{"rank": s.rank, "username": s.username, "mark": s.mark, "fraction": s.fraction,
                           "reached_at": s.reached_at.isoformat(), "you": s.user_id == viewer.id} for s in ranked],
            "unranked": unranked}


def set_open(session: Session, actor: User, course_id: int, exercise: Exercise, is_open: bool) -> ExerciseAssignment:
    """Opens the test's leaderboard to the course's students, or closes it again (the course's tutors and admins)."""
    _, test = course_test(session, course_id, exercise)
    if not teaches_course(session, actor, course_id):
        raise ExerciseRefused(403, "forbidden", gettext("Only the course's tutors open or close its leaderboards."),
                              "course_id")
    test.leaderboard_open = is_open
    session.flush()
    return test
