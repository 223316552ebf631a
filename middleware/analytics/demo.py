"""The usage `telelab up` seeds, so the demo tutor's Usage of the lab page has three weeks to show on a fresh lab:
sessions of the demo student and the demo classmates on lab-1 (each with a small recording of its odometry, so its
replay opens), the queue waits of their turns, one outage of lab-1 with the restart that ended it, a lesson watched
and a tour followed. Seeded once: a lab whose classmates already waited for a turn is left as it is."""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta

from flask import Flask
from sqlalchemy import select

from middleware.db import session_factory
from middleware.demo_course import DEMO_ROBOT, DEMO_SURVEY_ANSWERS
from middleware.models import User
from middleware.models.analytics import LearningEvent, QueueWait, RobotOutage
from middleware.models.recordings import Recording
from middleware.models.robots import RobotMaintenance
from middleware.models.teaching import Lesson, Tour
from middleware.recordings import channels, files
from middleware.recordings.parts import recordings_of
from protos.telelab.v1 import robot_pb2

DAYS = 21
STEP_S = 1  # one odometry reading a second: enough for a replay's trail


def _sessions(people: list[User], today: datetime) -> list[tuple[User, datetime, int, int]]:
    """(who, start, minutes, day index) of the demo sessions: each person every third day, at hours that vary."""
    found = []
    for day in range(DAYS):
        date = today - timedelta(days=DAYS - day)
        for index, person in enumerate(people):
            if (day + index) % 3:
                continue
            hour = 8 + (day * 5 + index * 7) % 11  # 8:00 to 18:00, a different hour most days
            start = date.replace(hour=hour, minute=(15 * index) % 60, second=0, microsecond=0)
            found.append((person, start, 10 + ((day + index) * 7) % 30, day))
    return found


def _write_track(app: Flask, recording_id: int, start: datetime, minutes: int) -> int:
    """A small odometry track (a loop, once a second) for the session's replay; its size on disk."""
    root = recordings_of(app).settings.directory
    writer = files.PartWriter(files.new_part_path(root, recording_id, "demo"), {"robot": DEMO_ROBOT, "demo": "true"})
    t0 = start.timestamp()
    for second in range(0, minutes * 60 + 1, STEP_S):
        angle = 2 * math.pi * second / 120.0
        pose = robot_pb2.Pose2D(x_m=0.5 + 0.6 * math.sin(angle), y_m=0.6 - 0.6 * math.cos(angle), theta_rad=angle)
        writer.write(channels.ODOMETRY, robot_pb2.Odometry(pose=pose, linear_mps=0.03, angular_radps=0.05),
                     int((t0 + second) * 1e9))
    writer.finish()
    return files.size_on_disk(root, recording_id)


def seed_demo_usage(app: Flask) -> list[str]:
    """The demo course's three weeks of use, when its classmates have none; what was added."""
    sessions = session_factory(app)
    today = datetime.now(UTC).replace(hour=0, minute=0, second=0, microsecond=0)
    written: list[tuple[int, datetime, int]] = []
    with sessions() as session, session.begin():
        names = ["student", *DEMO_SURVEY_ANSWERS]
        people = list(session.scalars(select(User).where(User.username.in_(names)).order_by(User.username)))
        classmates = [p.id for p in people if p.username != "student"]
        tutor = session.scalar(select(User).where(User.username == "tutor"))
        if not classmates or session.scalar(select(QueueWait.id).where(QueueWait.user_id.in_(classmates)).limit(1)):
            return []
        for person, start, minutes, day in _sessions(people, today):
            row = Recording(user_id=person.id, robot_name=DEMO_ROBOT, kind="turn", explicit=False, started_at=start,
                            ended_at=start + timedelta(minutes=minutes), status="recording",
                            end_reason="handed_over" if day % 2 else "turn_ended", command_count=minutes * 2,
                            skill_count=day % 3, plan_count=1 if day % 5 == 0 else 0)
            session.add(row)
            session.flush()
            written.append((row.id, start, minutes))
            wait_s = float((day * 37 + person.id * 53) % 400) if day % 4 else 0.0
            session.add(QueueWait(robot_name=DEMO_ROBOT, user_id=person.id, waited_from=start - timedelta(
                seconds=wait_s), granted_at=start, wait_s=wait_s))
        down = today - timedelta(days=5) + timedelta(hours=11)
        session.add(RobotOutage(robot_name=DEMO_ROBOT, started_at=down, ended_at=down + timedelta(minutes=25)))
        session.add(RobotMaintenance(robot_name=DEMO_ROBOT, actor_id=tutor.id if tutor else None, action="restart",
                                     outcome=f"{DEMO_ROBOT} restarted (demo).",
                                     created_at=down + timedelta(minutes=24)))
        lesson, tour = session.scalar(select(Lesson.id).limit(1)), session.scalar(select(Tour.id).limit(1))
        for index, person in enumerate(people):
            if lesson is not None:
                session.add(LearningEvent(user_id=person.id, kind="lesson_watched", object_id=lesson,
                                          at=today - timedelta(days=3 + index, hours=-10)))
            if tour is not None and index % 2 == 0:
                session.add(LearningEvent(user_id=person.id, kind="tour_followed", object_id=tour,
                                          at=today - timedelta(days=2 + index, hours=-14)))
    sizes = {recording_id: _write_track(app, recording_id, start, minutes) for recording_id, start, minutes in written}
    with sessions() as session, session.begin():
        for recording_id, size in sizes.items():
            stored = session.get(Recording, recording_id)
            if stored is not None:
                stored.status, stored.size_bytes = "ready", size
    return [f"three weeks of the demo course's use of {DEMO_ROBOT} ({len(written)} sessions, their queue waits, "
            "an outage) for Usage of the lab"]
