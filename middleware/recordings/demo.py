"""The demo recording `telelab up` seeds, so the replay page can be walked at once on a fresh lab: a minute of the
demo student driving a loop on lab-1, with commands, a goal and (when lab-1 answers) its scene. Real sessions are
recorded from the first turn on."""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta

from flask import Flask
from sqlalchemy import select

from middleware.db import session_factory
from middleware.models import User
from middleware.models.recordings import Recording
from middleware.recordings import channels, files
from middleware.recordings.parts import recordings_of
from middleware.robots.registry import robot_registry
from protos.telelab.v1 import robot_pb2

DEMO_ROBOT = "lab-1"
DEMO_SECONDS = 60
RATE_HZ = 10


def _pose(t: float) -> tuple[float, float, float]:
    """A loop of radius 0.8 m around (0.5, 0), once a minute."""
    angle = 2 * math.pi * t / DEMO_SECONDS
    return 0.5 + 0.8 * math.sin(angle), 0.8 - 0.8 * math.cos(angle), angle


def seed_demo_recording(app: Flask) -> list[str]:
    """The demo student's recording when they have none; what was added."""
    sessions = session_factory(app)
    with sessions() as session, session.begin():
        student = session.scalar(select(User).where(User.username == "student"))
        if student is None or session.scalar(select(Recording.id).where(Recording.user_id == student.id).limit(1)):
            return []
        start = datetime.now(UTC) - timedelta(days=1)
        recording = Recording(user_id=student.id, robot_name=DEMO_ROBOT, kind="turn", explicit=False,
                              started_at=start, ended_at=start + timedelta(seconds=DEMO_SECONDS),
                              end_reason="turn_ended", status="recording", command_count=DEMO_SECONDS // 5,
                              skill_count=1)
        session.add(recording)
        session.flush()
        recording_id = recording.id
    root = recordings_of(app).settings.directory
    part = files.new_part_path(root, recording_id, "demo")
    writer = files.PartWriter(part, {"robot": DEMO_ROBOT, "demo": "true"})
    t0 = start.timestamp()
    link = robot_registry(app).get(DEMO_ROBOT)
    if link is not None:
        try:
            writer.write(channels.ROBOT_INFO, link.info(), int(t0 * 1e9))
            writer.write(channels.SCENE, link.scene(max_age_s=60.0), int(t0 * 1e9))
        except Exception:  # noqa: BLE001 - lab-1 not up yet: the replay draws the trail without the scene
            pass
    speed = 2 * math.pi * 0.8 / DEMO_SECONDS
    for i in range(DEMO_SECONDS * RATE_HZ + 1):
        t = i / RATE_HZ
        x, y, theta = _pose(t)
        at = int((t0 + t) * 1e9)
        pose = robot_pb2.Pose2D(x_m=x, y_m=y, theta_rad=theta)
        writer.write(channels.ODOMETRY, robot_pb2.Odometry(pose=pose, linear_mps=speed,
                                                           angular_radps=2 * math.pi / DEMO_SECONDS), at)
        writer.write(channels.GROUND_TRUTH, robot_pb2.Pose2D(x_m=x + 0.02 * t / DEMO_SECONDS, y_m=y,
                                                             theta_rad=theta), at)
        writer.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=[1.5 + 0.5 * math.sin(t + k) for k in range(8)]),
                     at)
    for k in range(DEMO_SECONDS // 5):
        t = 5.0 * k + 1
        writer.write(channels.COMMANDS, channels.CommandRecord(
            sent_unix_s=t0 + t, sequence=k + 1, source="pad", action="drive", linear_mps=round(speed, 3),
            angular_radps=round(2 * math.pi / DEMO_SECONDS, 3), accepted=True), int((t0 + t) * 1e9))
    writer.write(channels.COMMANDS, channels.CommandRecord(
        sent_unix_s=t0 + 30, sequence=0, source="skill_panel", action="activate", skill="localization",
        accepted=True, outcome="demo-goal"), int((t0 + 30) * 1e9))
    writer.write(channels.GOALS, robot_pb2.GoalState(goal_id="demo-goal", skill="localization",
                                                     status=robot_pb2.GOAL_STATUS_SUCCEEDED), int((t0 + 45) * 1e9))
    writer.finish()
    with sessions() as session, session.begin():
        row = session.get(Recording, recording_id)
        if row is not None:
            row.status, row.size_bytes = "ready", files.size_on_disk(root, recording_id)
    return ["a recorded minute of the demo student's driving (Recordings)"]
