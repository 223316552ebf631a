"""Row locks that serialise a decision across worker processes (bookings, chat rate limits), and the election of
the one process that runs a cluster's periodic job.

PostgreSQL takes a row lock with SELECT ... FOR UPDATE. SQLite has no row locks, but one writer at a
time: starting the transaction with a write takes the database's write lock before anything is read,
so a second process waits (busy timeout) and then reads what the first one committed.
"""

from __future__ import annotations

import contextlib
from typing import Any, cast

from sqlalchemy import Connection, CursorResult, Engine, Update, select, text, update
from sqlalchemy.dialects.postgresql import insert as postgresql_insert
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import Session

from middleware.models import RobotControl, User


def _is_sqlite(session: Session) -> bool:
    return session.get_bind().dialect.name == "sqlite"


def rows_matched(session: Session, statement: Update) -> int:
    """How many rows a conditional UPDATE matched (0: its condition no longer held, e.g. another worker won)."""
    return cast("CursorResult[Any]", session.execute(statement)).rowcount


def lock_robot_control(session: Session, robot_name: str) -> RobotControl:
    """Locks the robot's robot_control row until the transaction ends, creating the row if missing; the row as
    stored now (one statement when it exists: a turn passing is latency every waiting user sees)."""
    if _is_sqlite(session):
        touched = rows_matched(session, update(RobotControl).where(RobotControl.robot_name == robot_name)
                               .values(robot_name=RobotControl.robot_name))
        if touched == 0:
            session.add(RobotControl(robot_name=robot_name))
            session.flush()
        control = session.get(RobotControl, robot_name, populate_existing=True)
    else:
        locked = (select(RobotControl).where(RobotControl.robot_name == robot_name).with_for_update()
                  .execution_options(populate_existing=True))
        control = session.scalar(locked)
        if control is None:
            # A concurrent creator blocks here until it commits; then the row exists and we lock it.
            session.execute(
                postgresql_insert(RobotControl).values(robot_name=robot_name, faulted=False)
                .on_conflict_do_nothing(index_elements=["robot_name"])
            )
            control = session.scalar(locked)
    assert control is not None
    return control


def lock_user(session: Session, user_id: int) -> None:
    """Locks the user's row until the transaction ends (per-user limits: allowance, chat rate)."""
    if _is_sqlite(session):
        session.execute(update(User).where(User.id == user_id).values(id=User.id))
        return
    session.execute(select(User.id).where(User.id == user_id).with_for_update())


CHAT_ROOM_LOCKS = 0x7E1E_C4A7  # the namespace of the advisory locks that order a chat room's messages


def lock_chat_room(session: Session, robot_name: str) -> None:
    """Holds the room's lock until the transaction ends, so its messages take their ids in the order they commit:
    a reader that saw id n has seen every committed id below it, and its cursor never passes one in flight."""
    if _is_sqlite(session):
        return  # one writer at a time: ids are already taken in commit order
    session.execute(text("SELECT pg_advisory_xact_lock(:space, hashtext(:room))"),
                    {"space": CHAT_ROOM_LOCKS, "room": robot_name})


class ClusterElection:
    """Elects one process of the cluster to run a periodic job: the holder of a PostgreSQL advisory lock, taken on
    a connection of its own and held while that connection lives. A process that dies closes its connection, and
    the lock goes to the next process that asks (each asks every tick, so within a tick). With SQLite there is one
    process: it always runs the job. The job must stay correct if two run (a lost connection may leave a former
    holder running one more tick): it is only who runs it that is elected, never what it may do.
    """

    def __init__(self, engine: Engine, key: int) -> None:
        self._engine, self._key = engine, key
        self._connection: Connection | None = None

    def leads(self) -> bool:
        """Whether this process runs the job now (takes the lock when it is free)."""
        if self._engine.dialect.name != "postgresql":
            return True
        try:
            if self._connection is None:
                self._connection = self._engine.connect()
                self._connection.execution_options(isolation_level="AUTOCOMMIT")
            if self._held:
                self._connection.execute(text("SELECT 1"))  # still connected, so still holding it
                return True
            self._held = bool(self._connection.execute(text("SELECT pg_try_advisory_lock(:key)"),
                                                       {"key": self._key}).scalar())
            return self._held
        except DBAPIError:
            self.resign()
            return False

    def resign(self) -> None:
        """Gives the job up: unlocks, then closes the connection (a closed connection releases the lock too, but
        only once the server has seen it close, which another process asking at once could miss)."""
        held, self._held = self._held, False
        if self._connection is not None:
            if held:
                with contextlib.suppress(DBAPIError):
                    self._connection.execute(text("SELECT pg_advisory_unlock(:key)"), {"key": self._key})
            with contextlib.suppress(DBAPIError):
                self._connection.invalidate()  # closed for real: back in the pool it would keep holding the lock
                self._connection.close()
            self._connection = None

    _held: bool = False
