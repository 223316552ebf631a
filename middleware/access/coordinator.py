"""Runs the round-robin rule for this process: transactions, the ticker, and handing tokens to robots."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from flask import Flask, current_app
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from middleware import events
from middleware.access import round_robin
from middleware.access.commands import hand_over
from middleware.access.heard import HeardBook
from middleware.access.liveness import RobotLiveness
from middleware.access.round_robin import AccessPolicy, QueueState
from middleware.db import session_factory
from middleware.locking import ClusterElection
from middleware.models import Course, CourseMembership, RobotControl
from middleware.robots.registry import robot_registry

log = logging.getLogger(__name__)
_EXTENSION_KEY = "telelab.access"
ACCESS_TICKER_LOCK = 0x7E1E_1AB0  # the advisory lock that elects the one process ticking every robot
HEARD_WRITE_S = 2.0  # how often the seats' "last heard" times noted by channels are written


def _utc_now() -> datetime:
    return datetime.now(UTC)


PriorityHook = Callable[[Session, str, datetime], int | None]
CheckInHook = Callable[[Session, str, int, datetime], object]
PriorityRobotsHook = Callable[[Session, datetime], "set[str] | None"]


@dataclass(frozen=True)
class AccessHooks:
    """What other areas add to the rule, handed in by create_app (access/ imports none of them).

    priority_user_id(session, robot, now): a user who goes first now (a booked slot, a live class);
    check_in(session, robot, user_id, now): called when a user joins a robot's queue (a booking's check-in);
    priority_robots(session, now): every robot priority_user_id may say something of (or keep its bookkeeping on)
    now, read for all robots at once; None: any robot may (the ticker then ticks every robot in turn).
    """

    priority_user_id: PriorityHook = lambda _session, _robot, _now: None
    check_in: CheckInHook = lambda _session, _robot, _user_id, _now: None
    priority_robots: PriorityRobotsHook = lambda _session, _now: None


def policy_for(app: Flask, hooks: AccessHooks) -> AccessPolicy:
    """The access policy from app's configuration and the hooks: grace period, turn length per user, priority."""

    def turn_length_s(session: Session, user_id: int) -> float:
        # A student in several courses gets the longest of their courses' turns.
        longest = session.scalar(
            select(func.max(Course.turn_length_s))
            .join(CourseMembership, CourseMembership.course_id == Course.id)
            .where(CourseMembership.user_id == user_id)
        )
        return float(longest) if longest else float(app.config["DEFAULT_TURN_LENGTH_S"])

    return AccessPolicy(float(app.config["ACCESS_GRACE_S"]), turn_length_s, hooks.priority_user_id)


class AccessCoordinator:
    """One per app and process: applies queue operations in their own transactions and keeps robots' tokens."""

    def __init__(self, app: Flask, hooks: AccessHooks | None = None, clock: Callable[[], datetime] = _utc_now) -> None:
        self.app = app
        self.hooks = hooks or AccessHooks()
        self.clock = clock
        self._sessions = session_factory(app)
        self._pushed_tokens: dict[str, str | None] = {}
        # (controller_id, token) per robot as this process last read or set it; only a hint (see
        # known_controller_token): the skill server, which refuses any other token, is the authority.
        self._known_controllers: dict[str, tuple[int | None, str | None]] = {}
        self._push_lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None
        self._liveness: RobotLiveness | None = None
        self.election = ClusterElection(self._sessions.kw["bind"], ACCESS_TICKER_LOCK)
        # Each robot's queue as last read, dropped when a change to it is announced (by any worker, through the
        # event bus): pages showing seats read memory, not the table, until something changes.
        self._bus = events.bus_of(self._sessions.kw["bind"])
        self._seen: dict[str, QueueState] = {}
        self._announced = 0  # counts announcements, so a read that overlapped one is not kept
        self._queue_watchers: set[Callable[[str | None], object]] = set()
        self._bus.listen(round_robin.QUEUE_TOPIC, self._forget_seen)
        self.heard = HeardBook(self._sessions, HEARD_WRITE_S)

    @property
    def policy(self) -> AccessPolicy:
        """The policy as configured now (tests and admins may change the settings while running)."""
        return policy_for(self.app, self.hooks)

    def apply(self, operation: Callable[..., QueueState], robot_name: str, *args: object,
              online: bool | None = None) -> QueueState:
        """Runs one round-robin operation in a transaction of its own, then hands the robot its token; online: the
        robot's last known answer (the ticker's), else the robot is asked now."""
        online = self._robot_online(robot_name, online)
        with self._sessions() as session, session.begin():
            state = operation(session, robot_name, *args, self.policy, self.clock(), online)
        if state.announced:  # this process's pages read it again at once; the bus tells the others (and us) soon
            self._announced += 1
            self._seen.pop(robot_name, None)
        self._known_controllers[robot_name] = (state.controller_id, state.token)
        if online:
            self.sync_token(state)
        return state

    def join(self, robot_name: str, user_id: int) -> QueueState:
        """The user connects to the robot (or reconnects within grace and keeps the seat)."""
        with self._sessions() as session, session.begin():
            self.hooks.check_in(session, robot_name, user_id, self.clock())
        return self.apply(round_robin.join, robot_name, user_id)

    def note_heard(self, robot_name: str, user_id: int, silent_s: float = 0.0) -> None:
        """The user is still connected: their client was last heard silent_s ago (the grace counts from then),
        written with this process's next batch of seat times."""
        self.heard.note(robot_name, user_id, self.clock() - timedelta(seconds=silent_s))

    def tick(self, robot_name: str) -> QueueState:
        """Brings the robot's queue up to date."""
        return self.apply(round_robin.tick, robot_name)

    def snapshot(self, robot_name: str) -> QueueState:
        """The robot's queue as stored now."""
        with self._sessions() as session:
            return round_robin.snapshot(session, robot_name, self.clock(), self.policy.grace_s)

    def seen_snapshot(self, robot_name: str) -> QueueState:
        """The robot's queue as last read here, read again only after a change was announced (any worker); the
        table itself while this process cannot hear announcements (its PostgreSQL listener is reconnecting)."""
        if self._bus.shared and not self._bus.listening.is_set():
            return self.snapshot(robot_name)
        state = self._seen.get(robot_name)
        if state is None:
            announced_before = self._announced
            state = self.snapshot(robot_name)
            if self._announced == announced_before:
                self._seen[robot_name] = state
        return state

    def _forget_seen(self, robot_name: str | None) -> None:
        self._announced += 1
        if robot_name is None:
            self._seen.clear()
        else:
            self._seen.pop(robot_name, None)
        for watcher in list(self._queue_watchers):
            watcher(robot_name)

    def watch_queues(self, watcher: Callable[[str | None], object]) -> Callable[[], None]:
        """Calls watcher(robot_name) (None: any robot) whenever a queue change is announced, from the event bus's
        thread (it must not block); returns what stops it."""
        self._queue_watchers.add(watcher)
        return lambda: self._queue_watchers.discard(watcher)

    def controller_token(self, robot_name: str, user_id: int, session: Session | None = None) -> str | None:
        """The token of user_id if they control the robot now, else None (one primary-key read, in the caller's
        session when given: a request already holds one)."""
        if session is None:
            with self._sessions() as own:
                return self.controller_token(robot_name, user_id, own)
        control = session.get(RobotControl, robot_name, populate_existing=True)
        self._known_controllers[robot_name] = (control.controller_id, control.token) if control else (None, None)
        return control.token if control is not None and control.controller_id == user_id else None

    def current_token(self, robot_name: str) -> str:
        """The token the robot obeys now, whoever holds it; "" while nobody has control (for supervisory actions,
        which must not take anyone's turn)."""
        with self._sessions() as session:
            control = session.get(RobotControl, robot_name, populate_existing=True)
            return (control.token or "") if control is not None and control.controller_id is not None else ""

    def known_controller_token(self, robot_name: str, user_id: int, session: Session | None = None) -> str | None:
        """controller_token without a database read when this process already knows user_id controls the robot.

        For calls the skill server checks: a token it refuses as not the controller's means the turn moved on
        in another process, and the caller asks controller_token again. A "no" is never taken from here, so
        a turn given elsewhere is seen at once.
        """
        return self.remembered_controller_token(robot_name, user_id) or self.controller_token(robot_name, user_id,
                                                                                              session)

    def remembered_controller_token(self, robot_name: str, user_id: int) -> str | None:
        """user_id's token when this process already knows they control the robot, else None: memory only, never
        a database read (the drive channel asks it on the loop, 20 times a second per driver)."""
        known = self._known_controllers.get(robot_name)
        return known[1] if known is not None and known[0] == user_id and known[1] else None

    def now(self) -> datetime:
        """The coordinator's clock."""
        return self.clock()

    def turn_length_s(self, user_id: int) -> float:
        """The turn length that applies to user_id."""
        with self._sessions() as session:
            return self.policy.turn_length_s(session, user_id)

    def sync_token(self, state: QueueState, force: bool = False) -> bool:
        """Makes sure the robot obeys the current controller's token (and only it); False if unreachable."""
        registry = robot_registry(self.app)
        link = registry.get(state.robot_name)
        if link is None:
            return False
        if registry.owner_of(state.robot_name) is not None:
            return True  # a personal robot obeys its owner's own token, whatever its queue says
        with self._push_lock:
            if not force and self._pushed_tokens.get(state.robot_name, "unset") == state.token:
                return True
            if not hand_over(link, state.token or ""):
                self._pushed_tokens.pop(state.robot_name, None)
                return False
            self._pushed_tokens[state.robot_name] = state.token
            return True

    def resend_token(self, robot_name: str) -> bool:
        """Hands the robot its current controller's token again (a restarted skill server forgot it)."""
        return self.sync_token(self.snapshot(robot_name), force=True)

    def start_ticker(self) -> None:
        """Ticks every robot's queue in the background (turn ends, grace periods, faults)."""
        if self._ticker is not None:
            return
        self._stop.clear()
        self._liveness = RobotLiveness(self._answers_now)
        self._ticker = threading.Thread(target=self._tick_forever, name="access-ticker", daemon=True)
        self._ticker.start()

    def stop_ticker(self) -> None:
        """Stops the background ticker (and gives its election up, so another process ticks at once)."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join(5)
            self._ticker = None
        if self._liveness is not None:
            self._liveness.close()
            self._liveness = None
        self.election.resign()

    def close(self) -> None:
        """This process is leaving: the ticker stops and what it heard of its seats last is written."""
        self.stop_ticker()
        self.heard.close()

    def _tick_forever(self) -> None:
        # Every process with a channel open runs this loop, but only the elected one ticks (PostgreSQL: one per
        # cluster; another takes over within a tick when it dies). Operations of users still run in their process.
        # A robot's answer is read from its last probe (RobotLiveness): a pass that waited for each robot in turn
        # held a vanished user's seat one call deadline longer per robot that did not answer.
        interval_s = float(self.app.config["ACCESS_TICK_S"])
        liveness = self._liveness
        while liveness is not None and not self._stop.wait(interval_s):
            if not self.election.leads():
                continue
            names = robot_registry(self.app).names()
            liveness.probe(names)
            answers = {name: online for name in names if (online := liveness.last(name)) is not None}
            try:
                self.tick_all(answers)  # a robot is ticked once its first probe answers (within a call deadline)
            except Exception:  # noqa: BLE001 - one bad pass must not stop the ticker
                log.exception("an access tick failed")

    def tick_all(self, online: dict[str, bool]) -> list[str]:
        """One pass of the ticker over the robots of online (each with whether it answered its last probe): one
        read of every robot's queue at once (round_robin.robots_due), then the locked rule in a transaction of its
        own for each robot with something due. A transaction per robot every tick was a fifth of a worker's time in
        a class of 50 (each with its priority reads: bookings, live classes, graded runs). The robots ticked."""
        for robot_name, answers in online.items():
            if not answers:
                self._robot_online(robot_name, False)  # a robot that stopped answering forgets its token
        registry = robot_registry(self.app)

        def handed(robot_name: str, token: str | None) -> bool:  # as sync_token would find it
            return registry.owner_of(robot_name) is not None or self._pushed_tokens.get(robot_name, "unset") == token

        with self._sessions() as session:
            now = self.clock()
            due = round_robin.robots_due(session, online, now, self.policy.grace_s, online,
                                         self.hooks.priority_robots(session, now), handed)
        for robot_name in due:
            try:
                self.apply(round_robin.tick, robot_name, online=online[robot_name])
            except Exception:  # noqa: BLE001 - one bad tick must not stop the others
                log.exception("access tick of %s failed", robot_name)
        return due

    def _answers_now(self, robot_name: str) -> bool:
        link = robot_registry(self.app).get(robot_name)
        return link is not None and link.is_online()

    def _robot_online(self, robot_name: str, known: bool | None = None) -> bool:
        online = self._answers_now(robot_name) if known is None else known
        if not online:
            with self._push_lock:
                self._pushed_tokens.pop(robot_name, None)  # a restarted robot forgot the token
        return online


def init_app(app: Flask, hooks: AccessHooks | None = None) -> AccessCoordinator:
    """Creates the coordinator of app with the other areas' hooks; the ticker starts with the first channel
    that needs it."""
    coordinator = app.extensions[_EXTENSION_KEY] = AccessCoordinator(app, hooks)
    return coordinator


def access_coordinator(app: Flask | None = None) -> AccessCoordinator:
    """The coordinator of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
