"""The round-robin rule of the 2003 paper's user agent, over the robot_control row and the queue.

"When only a single user is connected, no restrictions on usage are given. However, if multiple
users are simultaneously connected, only one is given access for a specified amount of time. Once
the time has expired, the next user in line will be given opportunity to control the robot and the
first user will be moved to the end of the waiting list."

Every function takes the session, the robot's name and `now`, locks the robot's control row first,
and leaves committing to the caller. Nothing here reads Flask state or talks to a robot.
"""

from __future__ import annotations

import secrets
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import overload

from sqlalchemy import delete, select, update
from sqlalchemy.orm import Session

from middleware import events
from middleware.access import pools
from middleware.locking import lock_robot_control, rows_matched
from middleware.models import QueueEntry, RobotControl
from middleware.models.analytics import QueueWait, RobotOutage

TURN_WARNING_S = 20.0
QUEUE_TOPIC = "queue"


@dataclass(frozen=True)
class AccessPolicy:
    """The numbers the rule needs, and where to ask for a user's turn length and booking priority."""

    grace_s: float
    turn_length_s: Callable[[Session, int], float]
    priority_user_id: Callable[[Session, str, datetime], int | None] = lambda _s, _r, _n: None


@dataclass(frozen=True)
class QueueState:
    """A robot's queue after a change: the controller, the waiting users in order, and the turn's end."""

    robot_name: str
    controller_id: int | None
    token: str | None
    waiting_ids: tuple[int, ...]
    turn_ends_at: datetime | None
    faulted: bool
    token_changed: bool = False
    announced: bool = False  # what a queue page shows changed (announced on the event bus)
    pool_waiting: int = 0  # pool waiters this robot could serve while nobody waits for it by name


@dataclass(frozen=True)
class Seat:
    """What one user sees of the queue."""

    in_queue: bool
    is_controller: bool
    position: int  # 0 for the controller, 1.. for the waiting users, -1 when not in the queue
    queue_size: int
    pool_waiting: int  # waiting for any robot of this kind: they may take this one's next turn
    turn_remaining_s: float | None  # the controller's countdown; None when the turn has no limit
    estimated_wait_s: float | None  # until this user gets control; 0 for the controller
    warning: bool  # the controller's turn ends soon
    faulted: bool


@overload
def _as_utc(moment: datetime) -> datetime: ...
@overload
def _as_utc(moment: datetime | None) -> datetime | None: ...
def _as_utc(moment: datetime | None) -> datetime | None:
    """SQLite hands back naive datetimes; every stored time is UTC."""
    if moment is None or moment.tzinfo is not None:
        return moment
    return moment.replace(tzinfo=UTC)


def lock_robot(session: Session, robot_name: str) -> RobotControl:
    """The robot's control row, locked for this transaction (created when missing)."""
    return lock_robot_control(session, robot_name)


def _entries(session: Session, robot_name: str) -> list[QueueEntry]:
    return list(session.scalars(
        select(QueueEntry).where(QueueEntry.robot_name == robot_name).order_by(QueueEntry.enqueued_at, QueueEntry.id)
    ))


def _grant(session: Session, control: RobotControl, user_id: int, now: datetime) -> None:
    waited_from = _as_utc(session.scalar(select(QueueEntry.enqueued_at).where(
        QueueEntry.robot_name == control.robot_name, QueueEntry.user_id == user_id))) or now
    waited_from = min(waited_from, now)
    # Usage analytics reads how long each turn was waited for (0 when the robot was free): written here, where
    # turns are granted, in the same transaction.
    session.add(QueueWait(robot_name=control.robot_name, user_id=user_id, waited_from=waited_from, granted_at=now,
                          wait_s=(now - waited_from).total_seconds()))
    control.controller_id = user_id
    control.token = secrets.token_urlsafe(32)
    control.turn_started_at = now
    control.turn_ends_at = None
    control.faulted = False


def _seen(control: RobotControl, entries: list[QueueEntry]) -> tuple[object, ...]:
    """What a queue page shows of the robot: who controls it, until when, faults, and who waits in which order."""
    return (control.controller_id, control.token, _as_utc(control.turn_ends_at), control.faulted,
            tuple(e.user_id for e in entries))


def _settle(session: Session, control: RobotControl, policy: AccessPolicy, now: datetime,
            robot_online: bool, entries: list[QueueEntry] | None = None, seen_before: tuple[object, ...] | None = None
            ) -> QueueState:
    """Applies the rule to the locked row: drops users gone past grace, grants, rotates, pauses on faults; a change
    is announced on the event bus (topic "queue", the robot's name) for every worker's queue pages. seen_before is
    the queue as it stood before the caller's own change (a join, a leave), so that change is announced too."""
    token_before, faulted_before = control.token, control.faulted
    entries = _entries(session, control.robot_name) if entries is None else entries
    seen_before = _seen(control, entries) if seen_before is None else seen_before
    cutoff = now - timedelta(seconds=policy.grace_s)
    for gone in [e for e in entries if _as_utc(e.last_seen_at) < cutoff]:
        session.delete(gone)
        entries.remove(gone)
    present = [e.user_id for e in entries]
    if control.controller_id not in present:
        control.controller_id = None
        control.token = None
        control.turn_ends_at = None
        control.faulted = False

    priority = policy.priority_user_id(session, control.robot_name, now)
    if (robot_online and priority is not None and priority not in present
            and pools.next_waiter(session, control.robot_name, now, policy.grace_s, only_user=priority) is not None
            and pools.take(session, control.robot_name, priority, now)):
        present.append(priority)  # a pool booking's holder, waiting in its pool: bound here at the slot
        entries = _entries(session, control.robot_name)
    if priority is not None and priority in present and control.controller_id != priority:
        _grant(session, control, priority, now)
    if robot_online and not present:
        bound = _bind_pool_waiter(session, control.robot_name, policy, now)
        if bound is not None:
            present.append(bound)
            entries = _entries(session, control.robot_name)

    if not robot_online:
        # Nobody loses a turn to a fault: the clock stops and the controller keeps the seat. With nobody in
        # the seat the flag still matters: it tells those waiting that no turn can start, not "0:00 to wait".
        control.faulted = True
        if control.controller_id is not None:
            control.turn_ends_at = None
    elif control.controller_id is None:
        control.faulted = False
        if present:
            _grant(session, control, present[0], now)
    elif control.faulted:
        control.faulted = False
        control.turn_ends_at = None  # a fresh turn, set below if others wait

    waiting = [u for u in present if u != control.controller_id]
    if robot_online and control.controller_id is not None:
        pool_waits = not waiting and pools.next_waiter(session, control.robot_name, now, policy.grace_s) is not None
        limited = (waiting or pool_waits) and control.controller_id != priority
        if not limited:
            control.turn_ends_at = None
        elif control.turn_ends_at is None:
            control.turn_ends_at = now + timedelta(seconds=policy.turn_length_s(session, control.controller_id))
        elif _as_utc(control.turn_ends_at) <= now:
            if not waiting and (bound := _bind_pool_waiter(session, control.robot_name, policy, now)) is not None:
                waiting = [bound]
            if waiting:
                previous = next(e for e in entries if e.user_id == control.controller_id)
                previous.enqueued_at = now  # to the end of the waiting list
                _grant(session, control, waiting[0], now)
                control.turn_ends_at = now + timedelta(seconds=policy.turn_length_s(session, waiting[0]))
                waiting = waiting[1:] + [previous.user_id]
            else:
                control.turn_ends_at = None  # the pool waiter went (or another robot took them): no one to hand to
    control.updated_at = now
    _note_outage(session, control.robot_name, faulted_before, control.faulted, now)
    session.flush()
    announced = _seen(control, _entries(session, control.robot_name)) != seen_before
    if announced:
        events.announce(session, QUEUE_TOPIC, control.robot_name)
    return QueueState(
        robot_name=control.robot_name,
        controller_id=control.controller_id,
        token=control.token,
        waiting_ids=tuple(waiting),
        turn_ends_at=_as_utc(control.turn_ends_at),
        faulted=control.faulted,
        token_changed=control.token != token_before,
        announced=announced,
    )


def _note_outage(session: Session, robot_name: str, before: bool, after: bool, now: datetime) -> None:
    """Opens a robot outage when the robot stops answering and closes it when it answers again (usage analytics'
    uptime and faults are read from these rows)."""
    if after and not before:
        session.add(RobotOutage(robot_name=robot_name, started_at=now))
    elif before and not after:
        session.execute(update(RobotOutage).where(RobotOutage.robot_name == robot_name, RobotOutage.ended_at.is_(None))
                        .values(ended_at=now))


def _bind_pool_waiter(session: Session, robot_name: str, policy: AccessPolicy, now: datetime) -> int | None:
    """Seats the first waiter of the robot's pool in its queue; their id, or None when nobody could be bound."""
    candidate = pools.next_waiter(session, robot_name, now, policy.grace_s)
    if candidate is not None and pools.take(session, robot_name, candidate, now):
        return candidate
    return None


def tick(session: Session, robot_name: str, policy: AccessPolicy, now: datetime,
         robot_online: bool = True) -> QueueState:
    """Brings the queue up to date with the clock and the robot's health."""
    return _settle(session, lock_robot(session, robot_name), policy, now, robot_online)


def robots_due(session: Session, robot_names: Iterable[str], now: datetime, grace_s: float,
               online: Mapping[str, bool], priority_robots: set[str] | None,
               handed: Callable[[str, str | None], bool] = lambda _name, _token: True) -> list[str]:
    """The robots among robot_names whose tick may change something now, read for all at once (four queries,
    however many robots): every other one would settle to what it is, since each user's own operation settles its
    robot at once and a tick only brings what time and faults change. Conservative: a robot is due with any
    seat past grace, a controller without a seat, a turn limit, a waiter, a fault to set or clear, pool waiters of its
    kind, one of priority_robots (the robots the priority rule may speak of now; None: any robot), or, online, a
    token stored that the caller may not have handed it (handed(name, token) false)."""
    names = list(robot_names)
    controls = {c.robot_name: c for c in session.scalars(select(RobotControl)
                                                         .where(RobotControl.robot_name.in_(names)))}
    seats: dict[str, list[QueueEntry]] = {}
    for entry in session.scalars(select(QueueEntry).where(QueueEntry.robot_name.in_(names))):
        seats.setdefault(entry.robot_name, []).append(entry)
    pooled = pools.robots_with_pool_waiters(session, names)
    cutoff = now - timedelta(seconds=grace_s)

    def due(name: str) -> bool:
        control, entries = controls.get(name), seats.get(name, [])
        if control is None or name in pooled or (priority_robots is None or name in priority_robots):
            return True
        if any(_as_utc(e.last_seen_at) < cutoff for e in entries) or control.turn_ends_at is not None:
            return True
        seated = {e.user_id for e in entries}
        if control.controller_id is not None and control.controller_id not in seated:
            return True
        if not online[name]:
            return not control.faulted
        return control.faulted or bool(seated - {control.controller_id}) or not handed(name, control.token)

    return [name for name in names if due(name)]


def join(session: Session, robot_name: str, user_id: int, policy: AccessPolicy, now: datetime,
         robot_online: bool = True) -> QueueState:
    """Connects a user to the robot: a new seat at the end, or the same seat refreshed (a reload)."""
    control = lock_robot(session, robot_name)
    entries = _entries(session, robot_name)
    seen_before = _seen(control, entries)
    entry = next((e for e in entries if e.user_id == user_id), None)
    if entry is None:
        session.add(QueueEntry(robot_name=robot_name, user_id=user_id, enqueued_at=now, last_seen_at=now))
    else:
        entry.last_seen_at = now
    session.flush()
    return _settle(session, control, policy, now, robot_online, seen_before=seen_before)


def heartbeat(session: Session, robot_name: str, user_id: int, now: datetime) -> bool:
    """Marks the user as still connected; False when they no longer hold a seat."""
    return bool(rows_matched(session, update(QueueEntry)
                             .where(QueueEntry.robot_name == robot_name, QueueEntry.user_id == user_id)
                             .values(last_seen_at=now)))


def leave(session: Session, robot_name: str, user_id: int, policy: AccessPolicy, now: datetime,
          robot_online: bool = True) -> QueueState:
    """Takes the user out of the queue; control passes on if they held it."""
    control = lock_robot(session, robot_name)
    seen_before = _seen(control, _entries(session, robot_name))
    session.execute(delete(QueueEntry).where(QueueEntry.robot_name == robot_name, QueueEntry.user_id == user_id))
    session.flush()
    return _settle(session, control, policy, now, robot_online, seen_before=seen_before)


def pass_turn(session: Session, robot_name: str, user_id: int, policy: AccessPolicy, now: datetime,
              robot_online: bool = True) -> QueueState:
    """The controller gives the turn to the next user early and goes to the end of the queue."""
    control = lock_robot(session, robot_name)
    if control.controller_id == user_id:
        entries = _entries(session, robot_name)
        if (any(e.user_id != user_id for e in entries)
                or pools.next_waiter(session, robot_name, now, policy.grace_s) is not None):
            control.turn_ends_at = now  # expires now: _settle rotates exactly as at the end of a turn
        return _settle(session, control, policy, now, robot_online, entries)
    return _settle(session, control, policy, now, robot_online)


def seat_of(state: QueueState, user_id: int, now: datetime, turn_length_s: float) -> Seat:
    """What user_id sees: position, queue size, countdown or estimated wait, and the end-of-turn warning."""
    size = len(state.waiting_ids) + (state.controller_id is not None)
    remaining = None
    if state.turn_ends_at is not None:
        remaining = max(0.0, (state.turn_ends_at - now).total_seconds())
    if state.controller_id == user_id:
        # Short turns would be "ending soon" from their first second; warn in their last quarter then.
        warn_within_s = min(TURN_WARNING_S, turn_length_s / 4)
        return Seat(True, True, 0, size, state.pool_waiting, remaining, 0.0,
                    remaining is not None and remaining <= warn_within_s, state.faulted)
    if user_id not in state.waiting_ids:
        return Seat(False, False, -1, size, state.pool_waiting, remaining, None, False, state.faulted)
    position = state.waiting_ids.index(user_id) + 1
    wait = None
    if state.faulted:
        pass  # no turn starts until the robot answers, so there is no wait to tell
    elif state.controller_id is None:
        wait = 0.0
    elif remaining is not None:
        wait = remaining + (position - 1) * turn_length_s
    return Seat(True, False, position, size, state.pool_waiting, remaining, wait, False, state.faulted)


def snapshot(session: Session, robot_name: str, now: datetime | None = None, grace_s: float = 0.0) -> QueueState:
    """The queue as stored, read without locking (for display; changes go through the locked functions); with now,
    the pool waiters the robot could serve while its controller is alone (their number is read as of now)."""
    control = session.get(RobotControl, robot_name)
    entries = _entries(session, robot_name)
    controller_id = control.controller_id if control else None
    alone = controller_id is not None and all(e.user_id == controller_id for e in entries)
    pool_waiting = pools.waiters_for(session, robot_name, now, grace_s) if alone and now is not None else 0
    return QueueState(
        robot_name=robot_name,
        controller_id=controller_id,
        token=control.token if control else None,
        waiting_ids=tuple(e.user_id for e in entries if e.user_id != controller_id),
        turn_ends_at=_as_utc(control.turn_ends_at) if control else None,
        faulted=bool(control and control.faulted),
        pool_waiting=pool_waiting,
    )
