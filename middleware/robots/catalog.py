"""The robots table: seeded from TELELAB_ROBOTS, read by the registry. No Flask request state in here."""

from __future__ import annotations

import re
from dataclasses import dataclass

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware import events
from middleware.config import RobotAddress
from middleware.models import Robot
from middleware.models.accounts import utc_now


@dataclass(frozen=True)
class RobotEntry:
    """One robot as the registry sees it: name, skill server address, title for people, enabled, kind."""

    name: str
    address: str
    title: str
    enabled: bool = True
    kind: str = ""


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
