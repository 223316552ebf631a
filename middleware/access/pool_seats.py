"""Waiting for any robot of a kind, as a user sees it: join, claim a free robot now, leave, and the expected wait.

The binding itself is the round-robin rule's (access/pools.py); this module runs it for the pool's robots at
once when a user joins, so a free robot is bound within the request, and estimates the wait otherwise. Everything
runs in the caller's unit of work (the request's session), so a claim is one transaction: free, locked and taken.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy.orm import Session

from middleware.access import pools, round_robin
from middleware.access.coordinator import AccessCoordinator
from middleware.access.round_robin import QueueState
from middleware.db import unit_of_work
from middleware.errors import Refused
from middleware.locking import lock_robot_control, lock_user
from middleware.robots.registry import robot_registry


@dataclass(frozen=True)
class PoolSeat:
    """A user's place for a kind: bound to a robot, or waiting at a position with an expected wait."""

    kind: str
    robot_name: str | None  # the robot the user was bound to (go to its console)
    position: int  # 1.. while waiting; 0 once bound; -1 when not in the pool's queue
    queue_size: int
    robots: int  # robots of the kind that answer now
    estimated_wait_s: float | None  # None: no robot of the kind answers, so no turn can start

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"kind": self.kind, "robot_name": self.robot_name, "position": self.position,
                "queue_size": self.queue_size, "robots": self.robots, "estimated_wait_s": self.estimated_wait_s}


def _about(seconds: float) -> str:
    minutes = round(seconds / 60)
    if minutes < 1:
        return f"{max(1, round(seconds))} s"
    return "1 minute" if minutes == 1 else f"{minutes} minutes"


class PoolFull(Refused):
    """No robot of the kind is free now: 409 with the expected wait, so the client can offer the queue."""

    def __init__(self, kind: str, robots: int, wait_s: float | None) -> None:
        when = ("no robot of it answers now" if wait_s is None
                else f"the next is expected free in about {_about(wait_s)}")
        super().__init__(409, "pool_full", f"All {robots} robots of kind {kind!r} are in use; {when}. "
                         "Join the pool's queue to be given the first that frees.", "kind")
        self.expected_wait_s = wait_s

    def to_dict(self) -> dict[str, object]:
        body = super().to_dict()
        body["error"]["expected_wait_s"] = self.expected_wait_s  # type: ignore[index]
        return body


class PoolSeats:
    """Pool operations in the caller's unit of work: every read and write goes through its session (with SQLite a
    second connection writing while that session holds the write lock would wait for it the whole busy timeout);
    robots are handed their new tokens through after_commit, once the change is committed."""

    def __init__(self, coordinator: AccessCoordinator, session: Session,
                 after_commit: Callable[[Callable[[], None]], None]) -> None:
        self._coordinator = coordinator
        self._session = session
        self._after_commit = after_commit

    def robots(self, kind: str) -> list[str]:
        """The kind's enabled robots; a 404 naming the field when the kind has none (an unknown pool)."""
        names = pools.robots_of_kind(self._session, kind)
        if not names:
            raise Refused(404, "unknown_pool", gettext("There is no pool of robots of kind %(kind)s.",
                                                       kind=repr(kind[:32])), "kind")
        return names

    def join(self, kind: str, user_id: int) -> PoolSeat:
        """Waits for any robot of kind (or refreshes the wait); bound at once when one is free."""
        names = self.robots(kind)
        if self._bound(kind, user_id) is None:
            pools.join(self._session, kind, user_id, self._coordinator.now())
            self._settle(names, user_id)
        return self.seat(kind, user_id)

    def claim(self, kind: str, user_id: int) -> PoolSeat:
        """A free robot of kind now, or PoolFull (409, with the expected wait) and nothing changed.

        One step: each robot that looks free is locked (its control row) and settled, and the user takes it only if
        it is still free under the lock, so of two students claiming the last robot at once one gets it and the
        other is refused; a claim never queues anyone. Robots are locked in the kind's order and the user's row after
        a robot's, as bookings do, so no two transactions wait for each other.
        """
        names = self.robots(kind)
        if self._bound(kind, user_id) is None:
            online = self._online(names)
            states = self._states(online)
            now, policy = self._coordinator.now(), self._coordinator.policy
            for name in [n for n in online if self._is_free(states[n])]:
                if not self._is_free(self._run(round_robin.tick, name, policy, now)):
                    continue  # taken meanwhile, or bound to a pool waiter who was first
                lock_user(self._session, user_id)  # the same student claiming twice at once takes one robot
                if self._bound(kind, user_id) is None:
                    self._run(round_robin.join, name, user_id, policy, now)
                return self.seat(kind, user_id)
            raise PoolFull(kind, len(online), self._wait_for(self._states(online), 1))
        return self.seat(kind, user_id)

    def leave(self, kind: str, user_id: int) -> None:
        """Stops waiting for kind (a seat already bound on a robot is that robot's to leave)."""
        self.robots(kind)
        pools.leave(self._session, kind, user_id)

    def seat(self, kind: str, user_id: int) -> PoolSeat:
        """Where user_id stands for kind now."""
        names = self.robots(kind)
        online = self._online(names)
        bound = self._bound(kind, user_id)
        waiting = pools.waiting(self._session, kind, self._coordinator.now(), self._coordinator.policy.grace_s)
        if bound is not None:
            return PoolSeat(kind, bound, 0, len(waiting), len(online), 0.0)
        if user_id not in waiting:
            return PoolSeat(kind, None, -1, len(waiting), len(online), None)
        position = waiting.index(user_id) + 1
        return PoolSeat(kind, None, position, len(waiting), len(online),
                        self._wait_for(self._states(online), position))

    def _run(self, operation: Callable[..., QueueState], *args: object) -> QueueState:
        """A round-robin operation (robot, ..., policy, now) in the caller's session; the robot gets its token after
        the commit."""
        state = operation(self._session, *args)

        def hand_token() -> None:
            self._coordinator.sync_token(state)

        self._after_commit(hand_token)
        return state

    def _bound(self, kind: str, user_id: int) -> str | None:
        return pools.bound_robot(self._session, kind, user_id)

    def _online(self, names: list[str]) -> list[str]:
        registry = robot_registry(self._coordinator.app)
        return [n for n in names if (link := registry.get(n)) is not None and link.is_online()]

    def _states(self, online: list[str]) -> dict[str, QueueState]:
        """The robots' queues as stored (read beside the session, unlocked: for estimates and a first look)."""
        return {name: self._coordinator.snapshot(name) for name in online}

    @staticmethod
    def _is_free(state: QueueState) -> bool:
        return state.controller_id is None and not state.waiting_ids and not state.faulted

    def _settle(self, names: list[str], user_id: int) -> None:
        """Ticks the kind's robots that could bind a waiter now (free, or at their turn's end) until one has bound
        user_id; the others are the background ticker's (a heartbeat of every waiter must not lock every robot)."""
        online, now, policy = self._online(names), self._coordinator.now(), self._coordinator.policy
        states = self._states(online)
        ready = [name for name, state in states.items()
                 if self._is_free(state) or (state.turn_ends_at is not None and state.turn_ends_at <= now)]
        for name in ready:  # locked in the kind's order before any is ticked: two joins never wait for each other
            lock_robot_control(self._session, name)
        for name in sorted(ready, key=lambda n: not self._is_free(states[n])):
            state = self._run(round_robin.tick, name, policy, now)
            if user_id == state.controller_id or user_id in state.waiting_ids:
                return

    def _wait_for(self, states: dict[str, QueueState], position: int) -> float | None:
        """When the position-th pool waiter can expect a turn: each robot frees after its current turn and its
        named waiters' turns; pool waiters take the robots in the order they free, one turn each."""
        if not states:
            return None
        now = self._coordinator.now()
        frees: list[float] = []
        turn_s = 0.0
        for state in states.values():
            turn_s = max(turn_s, self._coordinator.turn_length_s(state.controller_id or 0))
            if self._is_free(state):
                frees.append(0.0)
                continue
            remaining = (state.turn_ends_at - now).total_seconds() if state.turn_ends_at else turn_s
            frees.append(max(0.0, remaining) + len(state.waiting_ids) * turn_s)
        frees.sort()
        rounds, index = divmod(position - 1, len(frees))
        return frees[index] + rounds * turn_s


@contextmanager
def pool_seats_of(coordinator: AccessCoordinator) -> Iterator[PoolSeats]:
    """PoolSeats in a unit of work of its own (a script, a test): committed when the block ends, then the robots
    are handed their tokens."""
    later: list[Callable[[], None]] = []
    with unit_of_work(coordinator.app) as session:
        yield PoolSeats(coordinator, session, later.append)
    for callback in later:
        callback()
