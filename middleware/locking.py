"""Row locks that serialise a decision across worker processes (bookings, chat rate limits).

PostgreSQL takes a row lock with SELECT ... FOR UPDATE. SQLite has no row locks, but one writer at a
time: starting the transaction with a write takes the database's write lock before anything is read,
so a second process waits (busy timeout) and then reads what the first one committed.
"""

from __future__ import annotations

from typing import Any, cast

from sqlalchemy import CursorResult, Update, select, update
from sqlalchemy.dialects.postgresql import insert as postgresql_insert
from sqlalchemy.orm import Session

from middleware.models import RobotControl, User


def _is_sqlite(session: Session) -> bool:
    return session.get_bind().dialect.name == "sqlite"


def rows_matched(session: Session, statement: Update) -> int:
    """How many rows a conditional UPDATE matched (0: its condition no longer held, e.g. another worker won)."""
    return cast("CursorResult[Any]", session.execute(statement)).rowcount


def lock_robot_control(session: Session, robot_name: str) -> None:
    """Locks the robot's robot_control row until the transaction ends, creating the row if missing."""
    if _is_sqlite(session):
        touched = rows_matched(session, update(RobotControl).where(RobotControl.robot_name == robot_name)
                               .values(robot_name=RobotControl.robot_name))
        if touched == 0:
            session.add(RobotControl(robot_name=robot_name))
            session.flush()
        return
    # A concurrent creator blocks here until it commits; then the row exists and we lock it.
    session.execute(
        postgresql_insert(RobotControl).values(robot_name=robot_name, faulted=False)
        .on_conflict_do_nothing(index_elements=["robot_name"])
    )
    session.execute(select(RobotControl.robot_name).where(RobotControl.robot_name == robot_name).with_for_update())


def lock_user(session: Session, user_id: int) -> None:
    """Locks the user's row until the transaction ends (per-user limits: allowance, chat rate)."""
    if _is_sqlite(session):
        session.execute(update(User).where(User.id == user_id).values(id=User.id))
        return
    session.execute(select(User.id).where(User.id == user_id).with_for_update())
