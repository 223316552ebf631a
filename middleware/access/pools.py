"""Robot pools: the robots of one kind are interchangeable, so a user may wait for "any robot of kind K".

A pool's queue holds users not yet bound to a robot. The round-robin rule of each robot of the kind binds the
first of them when it can start a turn for them (its seat is free, or its controller's turn ends and nobody
waits for that robot by name): the pool entry becomes an ordinary seat in that robot's queue, so everything
after binding (turns, grace, tokens) is the robot's own rule. A pool waiter counts as "someone waiting" for
every robot of the kind, so a controller alone on one gets a limited turn.

Every function takes the caller's session and leaves committing to the caller; nothing here reads Flask state.
"""

from __future__ import annotations

from datetime import datetime, timedelta

from sqlalchemy import delete, func, select, update
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from middleware.locking import rows_matched
from middleware.models import PoolQueueEntry, QueueEntry, Robot


def robots_of_kind(session: Session, kind: str) -> list[str]:
    """The names of the enabled robots of kind, in the order they were added."""
    return list(session.scalars(select(Robot.name).where(Robot.kind == kind, Robot.enabled.is_(True))
                                .order_by(Robot.id)))


def kinds(session: Session) -> dict[str, list[str]]:
    """Every kind with enabled robots -> its robots' names."""
    pools: dict[str, list[str]] = {}
    for name, kind in session.execute(select(Robot.name, Robot.kind).where(Robot.enabled.is_(True))
                                      .order_by(Robot.kind, Robot.id)):
        pools.setdefault(kind, []).append(name)
    return pools


def _seated_in_kind(kind: str):  # noqa: ANN202 - a SQL subquery
    return (select(QueueEntry.user_id).join(Robot, Robot.name == QueueEntry.robot_name)
            .where(Robot.kind == kind))


def bound_robot(session: Session, kind: str, user_id: int) -> str | None:
    """The robot of kind in whose queue user_id holds a seat (bound from the pool, or joined by name)."""
    return session.scalar(select(QueueEntry.robot_name).join(Robot, Robot.name == QueueEntry.robot_name)
                          .where(Robot.kind == kind, QueueEntry.user_id == user_id).limit(1))


def join(session: Session, kind: str, user_id: int, now: datetime) -> None:
    """Puts user_id at the end of kind's pool queue, or refreshes their place (a heartbeat).

    One statement each way, never a read then a write: a robot's rule may bind the waiter (delete the entry) in
    another transaction between the two, and a waiter bound meanwhile stays bound rather than queued again; the
    same student joining twice at once leaves one entry.
    """
    waiting_entry = (PoolQueueEntry.kind == kind) & (PoolQueueEntry.user_id == user_id)
    if rows_matched(session, update(PoolQueueEntry).where(waiting_entry).values(last_seen_at=now)):
        return
    if bound_robot(session, kind, user_id) is not None:
        return
    dialect = postgresql if session.get_bind().dialect.name == "postgresql" else sqlite
    session.execute(dialect.insert(PoolQueueEntry)
                    .values(kind=kind, user_id=user_id, enqueued_at=now, last_seen_at=now)
                    .on_conflict_do_nothing(index_elements=["kind", "user_id"]))


def leave(session: Session, kind: str, user_id: int) -> None:
    """Takes user_id out of kind's pool queue."""
    session.execute(delete(PoolQueueEntry).where(PoolQueueEntry.kind == kind, PoolQueueEntry.user_id == user_id))


def waiting(session: Session, kind: str, now: datetime, grace_s: float) -> list[int]:
    """The users waiting in kind's pool queue, in order; those unheard of for longer than grace_s are dropped."""
    session.execute(delete(PoolQueueEntry).where(PoolQueueEntry.kind == kind,
                                                 PoolQueueEntry.last_seen_at < now - timedelta(seconds=grace_s)))
    return list(session.scalars(select(PoolQueueEntry.user_id).where(PoolQueueEntry.kind == kind)
                                .order_by(PoolQueueEntry.enqueued_at, PoolQueueEntry.id)))


def _servable(session: Session, robot_name: str, now: datetime, grace_s: float):  # noqa: ANN202 - a SQL condition
    """Which pool entries robot_name could serve: live ones of its kind's queue, not seated on a robot of the kind
    already; None for a robot without a pool (a personal robot, or one disabled meanwhile)."""
    kind = session.scalar(select(Robot.kind).where(Robot.name == robot_name, Robot.enabled.is_(True)))
    if kind is None:
        return None
    return ((PoolQueueEntry.kind == kind) & (PoolQueueEntry.last_seen_at >= now - timedelta(seconds=grace_s))
            & PoolQueueEntry.user_id.not_in(_seated_in_kind(kind)))


def robots_with_pool_waiters(session: Session, robot_names: list[str]) -> set[str]:
    """The robots among robot_names whose kind's pool queue holds anyone (live or not), in one query."""
    return set(session.scalars(select(Robot.name).where(Robot.name.in_(robot_names),
                                                        Robot.kind.in_(select(PoolQueueEntry.kind)))))


def next_waiter(session: Session, robot_name: str, now: datetime, grace_s: float,
                only_user: int | None = None) -> int | None:
    """The first live pool waiter robot_name could serve (one of its kind's queue, not seated on a robot of the
    kind already); only_user restricts the answer to that user (a pool booking's holder)."""
    servable = _servable(session, robot_name, now, grace_s)
    if servable is None:
        return None
    query = (select(PoolQueueEntry.user_id).where(servable)
             .order_by(PoolQueueEntry.enqueued_at, PoolQueueEntry.id).limit(1))
    if only_user is not None:
        query = query.where(PoolQueueEntry.user_id == only_user)
    return session.scalar(query)


def waiters_for(session: Session, robot_name: str, now: datetime, grace_s: float) -> int:
    """How many live pool waiters robot_name could serve (each counts as someone waiting for it)."""
    servable = _servable(session, robot_name, now, grace_s)
    if servable is None:
        return 0
    return session.scalar(select(func.count()).select_from(PoolQueueEntry).where(servable)) or 0


def take(session: Session, robot_name: str, user_id: int, now: datetime) -> bool:
    """Binds user_id from the pool queue to robot_name: the pool entry becomes a seat in the robot's queue.

    False if another robot bound them first (the conditional delete matched nothing), so two robots settling at
    once never seat the same waiter twice.
    """
    kind = session.scalar(select(Robot.kind).where(Robot.name == robot_name))
    if kind is None:
        return False
    removed = session.execute(delete(PoolQueueEntry).where(PoolQueueEntry.kind == kind,
                                                           PoolQueueEntry.user_id == user_id))
    if not getattr(removed, "rowcount", 0):
        return False
    session.add(QueueEntry(robot_name=robot_name, user_id=user_id, enqueued_at=now, last_seen_at=now))
    session.flush()
    return True
