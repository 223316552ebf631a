"""xAPI 1.0.3 statements (the learning-record convention LMSs read) built from the stored history: lessons watched,
tours followed, tests and exercises submitted, robot sessions held. A statement's id is derived from what it
records (uuid5 of the site and the row), so the same event is the same statement in every export and in the LRS.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterable
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.models import Course, CourseMembership, User
from middleware.models.accounts import as_utc
from middleware.models.analytics import LearningEvent
from middleware.models.assessment import Attempt, Exam
from middleware.models.exercises import Exercise, ExerciseAssignment, ExerciseRun
from middleware.models.recordings import Recording
from middleware.models.teaching import Lesson, Tour

XAPI_VERSION = "1.0.3"
VERBS = {
    "watched": "http://activitystrea.ms/schema/1.0/watch",
    "completed": "http://adlnet.gov/expapi/verbs/completed",
    "submitted": "http://activitystrea.ms/schema/1.0/submit",
    "attended": "http://adlnet.gov/expapi/verbs/attended",
}
ACTIVITY_TYPES = {
    "lesson": "http://adlnet.gov/expapi/activities/lesson",
    "tour": "http://adlnet.gov/expapi/activities/module",
    "test": "http://adlnet.gov/expapi/activities/assessment",
    "exercise": "http://adlnet.gov/expapi/activities/performance",
    "robot": "http://adlnet.gov/expapi/activities/simulation",
    "course": "http://adlnet.gov/expapi/activities/course",
}
KINDS = ("lesson_watched", "tour_followed", "test_submitted", "exercise_submitted", "session_held")


@dataclass(frozen=True)
class Built:
    """A statement and when what it records happened (for ordering and the outbox's look-back)."""

    at: datetime
    statement: dict[str, Any]
    user_id: int


def _duration(seconds: float) -> str:
    return f"PT{max(0.0, round(seconds, 2))}S"


class StatementBuilder:
    """Builds the statements of one site (homepage: the lab's address, the IRI every activity id starts with)."""

    def __init__(self, session: Session, homepage: str) -> None:
        self.session = session
        self.base = homepage.rstrip("/")
        self._courses: dict[int, list[dict[str, Any]]] = {}
        self._users: dict[int, User | None] = {}

    def statement_id(self, kind: str, row_id: int) -> str:
        """The statement's id, the same wherever and whenever it is built."""
        return str(uuid.uuid5(uuid.NAMESPACE_URL, f"{self.base}/#xapi/{kind}/{row_id}"))

    def _activity(self, kind: str, path: str, title: str) -> dict[str, Any]:
        return {"objectType": "Activity", "id": f"{self.base}/{path}",
                "definition": {"name": {"en": title or path}, "type": ACTIVITY_TYPES[kind]}}

    def _actor(self, user: User) -> dict[str, Any]:
        return {"objectType": "Agent", "name": user.username,
                "account": {"homePage": self.base + "/", "name": str(user.id)}}

    def _grouping(self, user_id: int) -> list[dict[str, Any]]:
        if user_id not in self._courses:
            courses = self.session.scalars(
                select(Course).join(CourseMembership, CourseMembership.course_id == Course.id)
                .where(CourseMembership.user_id == user_id, CourseMembership.role == "student").order_by(Course.id))
            self._courses[user_id] = [self._activity("course", f"courses/{c.id}", c.title) for c in courses]
        return self._courses[user_id]

    def _user(self, user_id: int) -> User | None:
        if user_id not in self._users:
            self._users[user_id] = self.session.get(User, user_id)
        return self._users[user_id]

    def _statement(self, kind: str, row_id: int, user_id: int, verb: str, obj: dict[str, Any], at: datetime,
                   result: dict[str, Any] | None = None) -> Built | None:
        user = self._user(user_id)
        if user is None:
            return None
        statement: dict[str, Any] = {
            "id": self.statement_id(kind, row_id), "actor": self._actor(user),
            "verb": {"id": VERBS[verb], "display": {"en": verb}}, "object": obj,
            "context": {"platform": "Telelab", "language": "en",
                        "contextActivities": {"grouping": self._grouping(user_id)}},
            "timestamp": as_utc(at).isoformat(), "version": XAPI_VERSION,
        }
        if not statement["context"]["contextActivities"]["grouping"]:
            del statement["context"]["contextActivities"]
        if result is not None:
            statement["result"] = result
        return Built(as_utc(at), statement, user_id)

    def learning_events(self, user_ids: Iterable[int] | None, since: datetime, until: datetime) -> list[Built]:
        """Lessons watched and tours followed."""
        query = select(LearningEvent).where(LearningEvent.at >= since, LearningEvent.at < until)
        if user_ids is not None:
            query = query.where(LearningEvent.user_id.in_(sorted(user_ids)))
        built = []
        for event in self.session.scalars(query.order_by(LearningEvent.id)):
            if event.kind == "lesson_watched":
                lesson = self.session.get(Lesson, event.object_id)
                obj = self._activity("lesson", f"lessons/{event.object_id}", lesson.title if lesson else "")
                one = self._statement(event.kind, event.id, event.user_id, "watched", obj, event.at,
                                      {"completion": True})
            else:
                tour = self.session.get(Tour, event.object_id)
                obj = self._activity("tour", f"tours/{event.object_id}", tour.title if tour else "")
                one = self._statement(event.kind, event.id, event.user_id, "completed", obj, event.at,
                                      {"completion": True})
            if one is not None:
                built.append(one)
        return built

    def tests(self, user_ids: Iterable[int] | None, since: datetime, until: datetime,
              course_id: int | None) -> list[Built]:
        """Tests submitted (the mark at submission; a tutor's later override is not a new statement)."""
        query = (select(Attempt, Exam).join(Exam, Exam.id == Attempt.exam_id)
                 .where(Attempt.status == "submitted", Attempt.submitted_at >= since, Attempt.submitted_at < until))
        if user_ids is not None:
            query = query.where(Attempt.user_id.in_(sorted(user_ids)))
        if course_id is not None:
            query = query.where(Exam.course_id == course_id)
        built = []
        for attempt, exam in self.session.execute(query.order_by(Attempt.id)):
            assert attempt.submitted_at is not None
            result: dict[str, Any] = {"completion": True, "duration": _duration(
                (as_utc(attempt.submitted_at) - as_utc(attempt.started_at)).total_seconds())}
            if attempt.auto_score is not None and attempt.max_score:
                raw, top = float(attempt.auto_score), float(attempt.max_score)
                result["score"] = {"raw": raw, "min": 0.0, "max": top,
                                   "scaled": round(min(1.0, max(0.0, raw / top)), 4)}
            obj = self._activity("test", f"tests/{exam.id}", exam.title)
            if (one := self._statement("test_submitted", attempt.id, attempt.user_id, "submitted", obj,
                                       attempt.submitted_at, result)) is not None:
                built.append(one)
        return built

    def exercises(self, user_ids: Iterable[int] | None, since: datetime, until: datetime,
                  course_id: int | None) -> list[Built]:
        """Exercise submissions graded (a course's: its assigned exercises and those assigned to no course)."""
        query = (select(ExerciseRun, Exercise).join(Exercise, Exercise.id == ExerciseRun.exercise_id)
                 .where(ExerciseRun.mode == "submission", ExerciseRun.status != "running",
                        ExerciseRun.ended_at.is_not(None), ExerciseRun.ended_at >= since, ExerciseRun.ended_at < until))
        if user_ids is not None:
            query = query.where(ExerciseRun.user_id.in_(sorted(user_ids)))
        if course_id is not None:
            elsewhere = select(ExerciseAssignment.exercise_id).where(ExerciseAssignment.course_id != course_id)
            here = select(ExerciseAssignment.exercise_id).where(ExerciseAssignment.course_id == course_id)
            query = query.where(Exercise.id.in_(here) | Exercise.id.not_in(elsewhere))
        built = []
        for run, exercise in self.session.execute(query.order_by(ExerciseRun.id)):
            assert run.ended_at is not None
            result: dict[str, Any] = {"completion": run.status == "graded", "duration": _duration(
                (as_utc(run.ended_at) - as_utc(run.started_at)).total_seconds())}
            if run.fraction is not None:
                result["score"] = {"scaled": round(min(1.0, max(0.0, float(run.fraction))), 4)}
            obj = self._activity("exercise", f"exercises/{exercise.id}", exercise.title)
            if (one := self._statement("exercise_submitted", run.id, run.user_id, "submitted", obj, run.ended_at,
                                       result)) is not None:
                built.append(one)
        return built

    def sessions(self, user_ids: Iterable[int] | None, since: datetime, until: datetime) -> list[Built]:
        """Robot sessions held (ended ones), with their length and what was sent."""
        query = select(Recording).where(Recording.ended_at.is_not(None), Recording.ended_at >= since,
                                        Recording.ended_at < until)
        if user_ids is not None:
            query = query.where(Recording.user_id.in_(sorted(user_ids)))
        built = []
        for row in self.session.scalars(query.order_by(Recording.id)):
            assert row.ended_at is not None
            extension = f"{self.base}/xapi/extensions/"
            result = {"duration": _duration((as_utc(row.ended_at) - as_utc(row.started_at)).total_seconds()),
                      "extensions": {extension + "commands": row.command_count, extension + "skills": row.skill_count,
                                     extension + "plans": row.plan_count, extension + "kind": row.kind,
                                     extension + "end-reason": row.end_reason or ""}}
            obj = self._activity("robot", f"robots/{row.robot_name}", row.robot_name)
            if (one := self._statement("session_held", row.id, row.user_id, "attended", obj, row.ended_at,
                                       result)) is not None:
                built.append(one)
        return built

    def built(self, user_ids: Iterable[int] | None, since: datetime, until: datetime,
              course_id: int | None = None) -> list[Built]:
        """Every statement of the people (None: everyone) for what happened in [since, until), oldest first."""
        ids = None if user_ids is None else sorted(user_ids)
        found = (self.learning_events(ids, since, until) + self.tests(ids, since, until, course_id)
                 + self.exercises(ids, since, until, course_id) + self.sessions(ids, since, until))
        return sorted(found, key=lambda b: (b.at, b.statement["id"]))

    def all(self, user_ids: Iterable[int] | None, since: datetime, until: datetime,
            course_id: int | None = None) -> list[dict[str, Any]]:
        """The statements alone (an export)."""
        return [b.statement for b in self.built(user_ids, since, until, course_id)]
