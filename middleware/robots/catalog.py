"""The robots table: seeded from TELELAB_ROBOTS, read by the registry. No Flask request state in here."""

from __future__ import annotations

import re
from dataclasses import dataclass

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware import events
from middleware.config import RobotAddress
from middleware.models import Robot, RobotKindSetting
from middleware.models.accounts import utc_now


@dataclass(frozen=True)
class RobotEntry:
    """One robot as the registry sees it: name, skill server address, title for people, enabled, kind."""

    name: str
    address: str
    title: str
    enabled: bool = True
    kind: str = ""


# Where the camera panel's picture comes from: the robot's JPEG video, or the view the browser draws from the scene
# and the odometry pose (simulated robots only: a robot standing for a real one keeps its video).
CAMERA_PICTURES = ("video", "drawn")


def camera_pictures(session: Session) -> dict[str, str]:
    """The kinds whose camera picture an admin chose, and the choice."""
    return {row.kind: row.camera_picture for row in session.scalars(select(RobotKindSetting))}


def camera_picture_of(session: Session, robot_name: str) -> tuple[str, str]:
    """(kind, default camera picture) of the robot called robot_name: its kind's setting, else "video"; a robot not
    in the table (a personal practice robot) is its own kind by its name."""
    kind = session.scalar(select(Robot.kind).where(Robot.name == robot_name)) or default_kind(robot_name)
    setting = session.get(RobotKindSetting, kind)
    return kind, setting.camera_picture if setting is not None else "video"


def default_kind(name: str) -> str:
    """The kind a robot gets unless an admin says otherwise: its name without a copy number ('lab-2' -> 'lab')."""
    return re.sub(r"-\d+$", "", name) or name


def seed_from_config(session: Session, configured: tuple[RobotAddress, ...]) -> None:
    """Inserts configured robots missing from the table; configuration wins for their addresses. Commits."""
    for robot in configured:
        row = session.scalar(select(Robot).where(Robot.name == robot.name))
        if row is None:
            session.add(Robot(name=robot.name, title=robot.title, address=robot.address, enabled=True,
                              kind=default_kind(robot.name)))
        elif row.address != robot.address:
            row.address, row.updated_at = robot.address, utc_now()
        if session.dirty or session.new:
            events.announce(session, "robots", robot.name)
        try:
            session.commit()
        except IntegrityError:  # another worker seeded the same name first; its row is as good as ours
            session.rollback()


def load_entries(session: Session) -> list[RobotEntry]:
    """Every robot in the table, enabled or not, in the order they were added."""
    return [RobotEntry(r.name, r.address, r.title, r.enabled, r.kind)
            for r in session.scalars(select(Robot).order_by(Robot.id))]
