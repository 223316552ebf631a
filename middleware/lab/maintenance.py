"""Who may diagnose and recover a robot from the web, and the robot's maintenance log (the 2003 paper's
telediagnosis and telemaintenance): an admin any robot; a tutor a lab robot (lab robots serve every course) or a
student's own robot of a course they teach. Services take the session and never read the request."""

from __future__ import annotations

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_student
from middleware.errors import Refused
from middleware.models import Role, User
from middleware.models.accounts import utc_now
from middleware.models.robots import RobotMaintenance

ACTIONS = ("restart", "dock", "clear_map")
LOG_SHOWN = 20


def require_maintainer(session: Session, actor: User, owner_id: int | None) -> None:
    """403 unless actor may diagnose and recover the robot (owner_id: a personal robot's owner, None: a lab robot)."""
    if actor.role == Role.ADMIN:
        return
    if actor.role == Role.TUTOR:
        if owner_id is None:
            return
        owner = session.get(User, owner_id)
        if owner is not None and teaches_student(session, actor, owner):
            return
    raise Refused(403, "forbidden", gettext("Only the tutors of the robot's courses and admins diagnose and restart "
                                            "robots."), "robot_name")


def record(session: Session, actor: User, robot_name: str, action: str, outcome: str) -> RobotMaintenance:
    """Writes an action taken and what came of it into the robot's maintenance log."""
    entry = RobotMaintenance(robot_name=robot_name, actor_id=actor.id, action=action, outcome=outcome[:500],
                             created_at=utc_now())
    session.add(entry)
    session.flush()
    return entry


def recent(session: Session, robot_name: str) -> list[tuple[RobotMaintenance, str | None]]:
    """The robot's latest maintenance actions, newest first, with who took them."""
    rows = session.execute(select(RobotMaintenance, User.username).outerjoin(User, User.id == RobotMaintenance.actor_id)
                           .where(RobotMaintenance.robot_name == robot_name)
                           .order_by(RobotMaintenance.id.desc()).limit(LOG_SHOWN))
    return [(entry, username) for entry, username in rows]
