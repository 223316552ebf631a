"""What a tutor may place in an LMS course by deep linking, and where each placed link opens.

Targets are "kind:key": console:<robot>, pool:<kind>, lesson:<id>, tour:<id>, exam:<id> (a test: the LMS makes a
gradebook column for it), exercise:<slug> (a Python exercise; a column too when it is a test of the course, out of
its points), class: (the course's class session).
Tests are those of the courses the tutor teaches.
"""

from __future__ import annotations

from dataclasses import dataclass

from flask import url_for
from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.access.pools import kinds
from middleware.courses.authority import taught_course_ids
from middleware.exercises.services import catalogue as exercise_catalogue
from middleware.exercises.services import ensure_catalogue
from middleware.lti.launches import Target
from middleware.models import Role, User
from middleware.models.assessment import Exam
from middleware.models.exercises import ExerciseAssignment
from middleware.models.teaching import Lesson, Tour


@dataclass(frozen=True)
class Placeable:
    """One item of the deep-linking picker."""

    target: str
    kind: str  # what a person reads, in their language: "Robot console", "Test", ...
    title: str
    score_maximum: float | None = None


def placeable(session: Session, actor: User, robot_names: list[str], course_id: int | None = None) -> list[Placeable]:
    """Everything actor may place, grouped by kind; an exercise that is a test of course_id (the Telelab course of
    the LMS course asking) gets a gradebook column out of the test's points."""
    items = [Placeable(f"console:{name}", gettext("Robot console"), name) for name in robot_names]
    items += [Placeable(f"pool:{kind}", gettext("Pool of robots"), gettext("Any free robot of kind %(kind)s",
                                                                           kind=kind))
              for kind in kinds(session)]
    items += [Placeable(f"lesson:{lesson.id}", gettext("Lesson"), lesson.title)
              for lesson in session.scalars(select(Lesson).order_by(Lesson.title, Lesson.id))]
    items += [Placeable(f"tour:{tour.id}", gettext("Tour"), tour.title)
              for tour in session.scalars(select(Tour).order_by(Tour.title, Tour.id))]
    exams = select(Exam).order_by(Exam.title, Exam.id)
    if actor.role != Role.ADMIN:
        exams = exams.where(Exam.course_id.in_(taught_course_ids(actor)))
    items += [Placeable(f"exam:{exam.id}", gettext("Test"), exam.title, 100.0) for exam in session.scalars(exams)]
    ensure_catalogue(session)  # the built-in exercises exist once asked for
    points: dict[int, float] = {} if course_id is None else {
        exercise_id: value for exercise_id, value in session.execute(select(
            ExerciseAssignment.exercise_id, ExerciseAssignment.points).where(
            ExerciseAssignment.course_id == course_id, ExerciseAssignment.points > 0))}
    items += [Placeable(f"exercise:{exercise.slug}", gettext("Python exercise, a test of the course")
                        if exercise.id in points else gettext("Python exercise"), exercise.title,
                        points.get(exercise.id))
              for exercise in exercise_catalogue(session)]
    items.append(Placeable("class:", gettext("Class session"), gettext("The course's class session")))
    return items


def destination(target: Target | None, course_id: int | None, teaches: bool) -> str:
    """The page a launch of target opens (the lab's home for none)."""
    if target is None:
        return url_for("lab.index")
    if target.kind == "console":
        return url_for("lab.console", robot_name=target.key)
    if target.kind == "pool":
        return url_for("pools.wait_page", kind=target.key)
    if target.kind == "lesson" and target.key.isdigit():
        return url_for("lessons.play", lesson_id=int(target.key))
    if target.kind == "tour" and target.key.isdigit():
        return url_for("tours.play", tour_id=int(target.key))
    if target.kind == "exam" and target.key.isdigit():
        return url_for("assessment_pages.exam_page", exam_id=int(target.key))
    if target.kind == "exercise" and target.key:
        return url_for("exercises.page", slug=target.key)
    if target.kind == "class":
        if teaches and course_id is not None:
            return url_for("classes.tutor_page", course_id=course_id)
        return url_for("classes.student_page")
    return url_for("lab.index")
