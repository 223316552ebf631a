"""Starts, finds and stops the learners' practice robots: simulated robots on the farm, one per user.

Each practice robot is a row of personal_robots (name, owner, the owner's controller token, address) and a
robot on the farm (middleware/farm). Any web worker finds a practice robot by name through the table and
reaches it through its own link, so the robots do not belong to the process that started them. The token is
given to the robot when it starts and again by the farm after a restart, so nobody else can ever control it.

Looking a robot up (every request and channel of a practice robot does) writes nothing: the use, and the new
address of a robot the farm moved, are noted in memory and written by the keeper (write_noted), the background
duty that also stops idle robots. Nor does it read each time: a running robot's row is kept by the process
(events.KeptAnswers) until its change is announced (TOPIC, the robot's name, in the transaction of every insert,
delete and new address), which every worker hears at once; this process drops it at once after its own changes.

A start is two steps: the row is claimed in the caller's unit of work (begin_start), and the farm starts the
robot once that is committed (PendingStart.run, an after_commit hook of the request), so other workers see the
claim before the robot exists and nothing here commits a request's session. A claim whose start never finished
(its process died between the commit and the start) is released after START_DEADLINE_S by any keeper, or
replaced when its owner starts again.

The robot registry resolves `practice-...` names through the manager for their owners only, so a practice
robot opens in the lab console (/lab/<name>) with every panel, and every robot page, API and channel
answers anyone else with a 404.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import math
import os
import re
import secrets
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta

from flask import Flask, current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import delete, func, or_, select, update
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import Session, sessionmaker

from middleware import events
from middleware.config import ConfigError
from middleware.db import session_factory
from middleware.errors import Refused
from middleware.farm.base import FarmFull, FarmUnavailable, RobotFarm, RobotSpec
from middleware.locking import rows_matched
from middleware.models.accounts import as_utc, utc_now
from middleware.models.farm import ClassSession, PersonalRobotRecord
from middleware.robots.link import RobotLink, answers_at
from middleware.robots.registry import PersonalRobot, RobotRegistry

log = logging.getLogger(__name__)
_EXTENSION_KEY = "telelab.practice"
DEFAULT_IDLE_S = 900.0
PRACTICE_PREFIX = "practice-"
PLAIN_USERNAME = re.compile(r"^[a-z0-9][a-z0-9_-]{0,22}$")  # fits the 32-character robot names as it is
START_DEADLINE_S = 120.0  # a claim still without an address this long after it was written is a start that died
REFIND_AFTER_S = 1.0  # a robot unreachable this long is looked up on the farm again (it may have moved)
TOPIC = "practice-robots"  # announced with a robot's name whenever its row is inserted, deleted or moved
KNOWN_S = 1.0  # how long a process keeps a running robot's row while it may miss an announcement
HEARD_KNOWN_S = 60.0  # while it hears them: the change's announcement drops the row at once (a read per robot per
# worker a minute, a net under that: at 15 s, a fifth of a 3-worker class's transactions)


class PracticeCapReached(Refused):
    """Every practice slot the lab allows is taken (429); the message says how many and what to do."""

    def __init__(self, message: str) -> None:
        super().__init__(429, "practice_cap_reached", message)


class PracticeStartFailed(Refused):
    """The practice robot did not start, or is starting already (503)."""

    def __init__(self, message: str) -> None:
        super().__init__(503, "practice_start_failed", message)


def watched(link: RobotLink) -> bool:
    """Whether someone watches one of the robot's streams now (a console open on it)."""
    return any(hub.viewer_count > 0 for hub in (link.camera, link.telemetry, link.localization))


@dataclass(frozen=True)
class PendingStart:
    """A claim written in the caller's unit of work, whose robot the farm starts once it is committed; and the
    robot it replaced (another scene's, or a start that died), stopped first."""

    manager: PracticeManager
    name: str
    token: str
    scene: str
    replaced: str | None = None

    def run(self) -> PracticeRobot:
        """Stops the replaced robot and starts the claimed one; Refused when the farm cannot (the claim is
        released)."""
        if self.replaced is not None:
            self.manager.finish_stop(self.replaced)
        return self.manager.launch(self.name, self.token, self.scene)

    def run_quietly(self) -> None:
        """run() for an after_commit hook: a start the farm refuses releases its claim, and the page reads the
        robot off instead of starting."""
        try:
            self.run()
        except Refused as refusal:
            log.warning("practice robot %s did not start: %s", self.name, refusal.message)
        except Exception:  # noqa: BLE001 - the request is answered already; the claim is released
            log.exception("practice robot %s did not start", self.name)


@dataclass(frozen=True)
class _Row:
    """What a lookup reads of a running robot's row."""

    name: str
    owner_id: int
    username: str
    token: str
    address: str


def announce_change(session: Session, name: str) -> None:
    """Announces that the row of the practice robot called name changes in session's transaction."""
    events.announce(session, TOPIC, name)


@dataclass(frozen=True)
class PracticeRobot:
    """One learner's running robot: its name, owner, this process's link to it and the owner's token."""

    name: str
    owner_id: int
    username: str
    link: RobotLink
    token: str


def _insert_unless_taken(session: Session, claim: dict[str, object]) -> bool:
    """Inserts the claim's row in session unless its owner (or name) has one, committed by another request meanwhile:
    INSERT ... ON CONFLICT DO NOTHING, which leaves the caller's transaction usable where a failed INSERT would
    abort it (PostgreSQL), and a savepoint would commit it (SQLite's driver releases an outermost one as a COMMIT).
    Whether it was inserted."""
    dialect = session.get_bind().dialect.name
    insert = postgresql.insert if dialect == "postgresql" else sqlite.insert
    inserted = insert(PersonalRobotRecord).values(**claim).on_conflict_do_nothing()
    return session.scalar(inserted.returning(PersonalRobotRecord.name)) is not None


def practice_name(username: str, owner_id: int) -> str:
    """The robot name of a user's practice robot: unique, URL-safe and at most 32 characters.

    `practice-<username>` when the username fits as it is; `practice-_<id>` otherwise (no username starts
    with "_", so the two forms never meet).
    """
    if PLAIN_USERNAME.fullmatch(username):
        return PRACTICE_PREFIX + username
    return f"{PRACTICE_PREFIX}_{owner_id}"


def read_limits(environ: dict[str, str] | None = None) -> tuple[int | None, float]:
    """TELELAB_PRACTICE_CAP (optional: none means as many as the farm holds) and TELELAB_PRACTICE_IDLE_S."""
    env = os.environ if environ is None else environ
    raw_cap, raw_idle = env.get("TELELAB_PRACTICE_CAP", ""), env.get("TELELAB_PRACTICE_IDLE_S", str(DEFAULT_IDLE_S))
    cap = None
    if raw_cap.strip():
        try:
            cap = int(raw_cap)
        except ValueError:
            raise ConfigError(f"TELELAB_PRACTICE_CAP must be a whole number, not {raw_cap!r}.") from None
        if not 0 <= cap <= 10_000:
            raise ConfigError("TELELAB_PRACTICE_CAP must be between 0 and 10000.")
    try:
        idle_s = float(raw_idle)
    except ValueError:
        raise ConfigError(f"TELELAB_PRACTICE_IDLE_S must be a number of seconds, not {raw_idle!r}.") from None
    if not 5 <= idle_s <= 86400:
        raise ConfigError("TELELAB_PRACTICE_IDLE_S must be between 5 and 86400 seconds.")
    return cap, idle_s


class PracticeManager:
    """The lab's practice robots: as many as the farm holds (or `cap`), each stopped after `idle_s` unused."""

    def __init__(self, farm: RobotFarm, sessions: sessionmaker[Session], idle_s: float, cap: int | None = None,
                 rpc_timeout_s: float = 1.0, scene: str = "lab", clock: Callable[[], datetime] = utc_now,
                 start_deadline_s: float = START_DEADLINE_S) -> None:
        self.farm, self.cap, self.idle_s, self.scene = farm, cap, idle_s, scene
        self.start_deadline_s = start_deadline_s
        self._sessions = sessions
        self._rpc_timeout_s = rpc_timeout_s
        self._clock = clock
        self._links: dict[str, RobotLink] = {}
        self._used_at: dict[str, datetime] = {}  # name -> its latest use in this process, not yet written
        self._moved: dict[str, tuple[str, str]] = {}  # name -> (address in the table, where the farm has it now)
        self._refound_at: dict[str, float] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._keeper: threading.Thread | None = None
        self._rows: events.KeptAnswers[str, _Row | None] = events.KeptAnswers(sessions.kw["bind"], TOPIC, KNOWN_S,
                                                                             HEARD_KNOWN_S)

    def get(self, owner_id: int) -> PracticeRobot | None:
        """owner_id's running practice robot, if any (and counts as a use)."""
        return self._running(PersonalRobotRecord.owner_id == owner_id)

    def by_name(self, name: str) -> PracticeRobot | None:
        """The running practice robot called name, whoever owns it (the caller checks the owner)."""
        if not name.startswith(PRACTICE_PREFIX):
            return None
        return self._running(PersonalRobotRecord.name == name, name)

    def personal_robot(self, name: str) -> PersonalRobot | None:
        """The registry's view of the practice robot called name (its resolver)."""
        robot = self.by_name(name)
        if robot is None:
            return None
        return PersonalRobot(robot.link, f"Practice robot of {robot.username}", robot.owner_id, robot.token)

    def count(self) -> int:
        """How many practice robots run or are starting now, in the whole lab."""
        with self._sessions() as session:
            return session.scalar(select(func.count()).select_from(PersonalRobotRecord)) or 0

    def limit(self) -> int:
        """How many practice robots may run at once: the cap if set, else what the farm holds."""
        capacity = self.farm.capacity().robots
        return capacity if self.cap is None else min(self.cap, capacity)

    def starting(self, owner_id: int) -> bool:
        """Whether owner_id's practice robot is claimed and not started yet (within the start deadline)."""
        with self._sessions() as session:
            record = session.scalar(select(PersonalRobotRecord).where(PersonalRobotRecord.owner_id == owner_id))
            return record is not None and not record.address and not self._start_died(record)

    def begin_start(self, session: Session, owner_id: int, username: str, class_session_id: int | None = None,
                    scene: str | None = None) -> PendingStart | None:
        """Claims owner_id's practice robot in session (the caller's unit of work, which commits it); the start to
        run once committed, or None when the robot runs (in scene, when one was asked) or is starting already.

        scene (the manager's own by default) and class_session_id (the robot is the student's in that class
        session, kept while it is open): a robot already running another scene than the one asked (or a class's)
        is replaced. Refused when the lab is full; the caller's unit of work then keeps nothing.

        Two claims at once (the owner's two tabs, or a plan run beside a start): the second one's insert waits for
        the first's row, committed meanwhile, inserts nothing and answers None (starting already); no error, so the
        caller's unit of work goes on: nothing here rolls the caller's session back."""
        wanted = scene or self.scene
        record = session.scalar(select(PersonalRobotRecord).where(PersonalRobotRecord.owner_id == owner_id))
        replaced = None
        if record is not None:
            in_scene = (class_session_id is None and scene is None) or record.scene == wanted
            if (record.address and in_scene) or (not record.address and not self._start_died(record)):
                if class_session_id is not None:
                    record.class_session_id = class_session_id
                    session.flush()
                return None
            replaced = record.name  # by name and token: a keeper releasing the same dead claim meanwhile is no error
            session.execute(delete(PersonalRobotRecord).where(PersonalRobotRecord.name == replaced,
                                                              PersonalRobotRecord.token == record.token))
            session.expunge(record)
            announce_change(session, replaced)
        limit = self.limit()
        if (session.scalar(select(func.count()).select_from(PersonalRobotRecord)) or 0) >= limit:
            raise PracticeCapReached(gettext("All %(limit)s practice robots are in use. Try again in a few minutes, "
                                             "or watch a lab robot in the meantime.", limit=limit))
        name, token, now = practice_name(username, owner_id), secrets.token_urlsafe(32), self._clock()
        claim = {"name": name, "owner_id": owner_id, "owner_name": username, "scene": wanted, "token": token,
                 "address": "", "backend": self.farm.backend, "started_at": now, "last_used_at": now,
                 "class_session_id": class_session_id}
        if not _insert_unless_taken(session, claim):  # another request claimed it first: that start is under way
            return None
        announce_change(session, name)
        self.start_keeper()  # this process releases the claim if its start dies
        return PendingStart(self, name, token, wanted, replaced)

    def launch(self, name: str, token: str, scene: str) -> PracticeRobot:
        """Starts the committed claim (name, token) on the farm and records its address; Refused when the farm
        cannot (the claim is released) or the claim went meanwhile (stopped, or released as a dead start)."""
        try:
            robot = self.farm.start(RobotSpec(name, scene, token))
        except (FarmFull, FarmUnavailable) as error:
            self._release(name, token)
            log.warning("practice robot %s did not start: %s", name, error.message)
            if isinstance(error, FarmFull):
                raise PracticeCapReached(error.message) from None
            raise PracticeStartFailed(gettext("Your practice robot did not start. Try again in a moment.")) from None
        except BaseException:
            self._release(name, token)
            raise
        with self._sessions() as session, session.begin():
            recorded = rows_matched(session, update(PersonalRobotRecord).where(
                PersonalRobotRecord.name == name, PersonalRobotRecord.token == token)
                .values(address=robot.address, last_used_at=self._clock()))  # running from now: not idle yet
            announce_change(session, name)
        self._rows.drop(name)
        started = self.by_name(name) if recorded else None
        if started is None or started.token != token:
            if not recorded:  # released meanwhile: nobody's robot
                self.farm.stop(name)
            raise PracticeStartFailed(gettext("Your practice robot was stopped while it started. Start it again."))
        return started

    def start(self, owner_id: int, username: str, class_session_id: int | None = None,
              scene: str | None = None) -> PracticeRobot:
        """owner_id's practice robot, claimed and started now if not running, in units of work of its own: for
        background duties (a class's start), never a request (which claims with begin_start and starts after its
        commit); refused when the lab or the farm is full, or while another start of it is under way."""
        with self._sessions() as session, session.begin():
            pending = self.begin_start(session, owner_id, username, class_session_id, scene)
        if pending is not None:
            return pending.run()
        running = self.get(owner_id)
        if running is None:
            raise PracticeStartFailed(gettext("Your practice robot is starting already; wait a few seconds."))
        return running

    def begin_stop(self, session: Session, owner_id: int) -> str | None:
        """Removes owner_id's practice robot's row in session (the caller's unit of work); the robot's name, whose
        process finish_stop ends once that is committed, or None when there was none."""
        record = session.scalar(select(PersonalRobotRecord).where(PersonalRobotRecord.owner_id == owner_id))
        if record is None:
            return None
        session.delete(record)
        session.flush()
        announce_change(session, record.name)
        return record.name

    def finish_stop(self, name: str) -> None:
        """Ends the robot whose row begin_stop removed (after the commit)."""
        self._forget(name)
        self.farm.stop(name)

    def stop(self, owner_id: int) -> bool:
        """Stops owner_id's practice robot in a unit of work of its own (background duties); False when there was
        none."""
        with self._sessions() as session, session.begin():
            name = self.begin_stop(session, owner_id)
        if name is None:
            return False
        self.finish_stop(name)
        return True

    def begin_stop_named(self, session: Session, name: str) -> str | None:
        """begin_stop for the practice robot called name (an admin's stop on the farm's page), in session (the
        caller's unit of work); its name, whose process finish_stop ends once that is committed, or None."""
        owner_id = session.scalar(select(PersonalRobotRecord.owner_id).where(PersonalRobotRecord.name == name))
        return None if owner_id is None else self.begin_stop(session, owner_id)

    def stop_named(self, name: str) -> bool:
        """Stops the practice robot called name in a unit of work of its own (an operator's `telelab farm stop`);
        False when there is none."""
        with self._sessions() as session:
            owner_id = session.scalar(select(PersonalRobotRecord.owner_id).where(PersonalRobotRecord.name == name))
        return owner_id is not None and self.stop(owner_id)

    def stop_idle(self) -> list[str]:
        """Stops every robot unused for idle_s (a console watching it counts as a use; a robot of an open class
        session is never idle); returns their names."""
        for name, link in list(self._links.items()):
            if watched(link):
                self._touch(name)
        self.write_noted()
        cutoff = self._clock() - timedelta(seconds=self.idle_s)
        with self._sessions() as session:
            in_open_class = select(ClassSession.id).where(ClassSession.ended_at.is_(None))
            idle = session.execute(select(PersonalRobotRecord.name, PersonalRobotRecord.owner_id).where(
                PersonalRobotRecord.last_used_at <= cutoff, PersonalRobotRecord.address != "",
                or_(PersonalRobotRecord.class_session_id.is_(None),
                    PersonalRobotRecord.class_session_id.not_in(in_open_class)))).all()
        for name, owner_id in idle:
            log.info("stopping idle practice robot %s", name)
            self.stop(owner_id)
        return [name for name, _ in idle]

    def shutdown(self) -> None:
        """Stops every practice robot of the lab and the keeper (tests, and `telelab up` ending the lab)."""
        self.close()
        with self._sessions() as session:
            owners = session.scalars(select(PersonalRobotRecord.owner_id)).all()
        for owner_id in owners:
            self.stop(owner_id)

    def close(self) -> None:
        """This process lets go: the keeper stops and the links close; the robots run on for other workers."""
        self._stop.set()
        if self._keeper is not None and self._keeper is not threading.current_thread():
            self._keeper.join(5)
        for name in list(self._links):
            self._forget(name)

    def start_keeper(self) -> None:
        """Stops idle robots in the background."""
        with self._lock:
            if self._keeper is not None or self._stop.is_set():
                return
            self._keeper = threading.Thread(target=self._keep_forever, name="practice-keeper", daemon=True)
            self._keeper.start()

    def release_dead_starts(self) -> list[str]:
        """Releases the claims whose start did not finish within START_DEADLINE_S (the process that claimed one
        died between its commit and the farm's start); their names."""
        cutoff = self._clock() - timedelta(seconds=self.start_deadline_s)
        with self._sessions() as session, session.begin():
            dead = session.execute(select(PersonalRobotRecord.name, PersonalRobotRecord.token).where(
                PersonalRobotRecord.address == "", PersonalRobotRecord.started_at < cutoff)).all()
            for name, token in dead:
                session.execute(delete(PersonalRobotRecord).where(PersonalRobotRecord.name == name,
                                                                  PersonalRobotRecord.token == token))
                announce_change(session, name)
        for name, _token in dead:
            log.warning("practice robot %s: its start did not finish within %.0f s; its claim is released",
                        name, self.start_deadline_s)
            with contextlib.suppress(FarmUnavailable):
                self.farm.stop(name)  # a start that finished after all, too late
        return [name for name, _ in dead]

    def _start_died(self, record: PersonalRobotRecord) -> bool:
        return as_utc(record.started_at) < self._clock() - timedelta(seconds=self.start_deadline_s)

    def forget_lost(self) -> list[str]:
        """Removes the rows of robots that run nowhere (the local farm's robots end with their process; a start
        that never finished); returns their names.

        A robot this process's farm does not know may belong to another process (the web server, while a
        `telelab` command runs): it is lost only if it does not answer at its address either."""
        stale_start = self._clock() - timedelta(seconds=self.start_deadline_s)
        with self._sessions() as session:
            records = session.execute(select(PersonalRobotRecord.name, PersonalRobotRecord.address,
                                             PersonalRobotRecord.started_at)).all()
        lost = [name for name, address, started_at in records
                if (address and self.farm.find(name) is None and not answers_at(name, address))
                or (not address and as_utc(started_at) < stale_start)]
        for name in lost:
            self._release(name)
        return lost

    def _running(self, where, kept_as: str | None = None) -> PracticeRobot | None:
        """The running robot whose row where finds; kept_as: its name, under which this process keeps the row (only a
        running robot's: a robot starting is looked up again)."""
        row = self._read_row(where) if kept_as is None else self._rows.get(
            kept_as, lambda: self._read_row(where), lambda found: math.inf if found is not None else 0.0)
        if row is None:
            return None
        name, owner_id, username, token, address = row.name, row.owner_id, row.username, row.token, row.address
        moved = self._moved.get(name)
        if moved is not None and moved[0] == address:  # found elsewhere, not written yet: go where it is now
            address = moved[1]
        self.start_keeper()  # this process reaps idle robots once it serves one (a worker that never does, does not)
        link = self._link(name, address)
        if link.unreachable_since is not None and time.monotonic() - link.unreachable_since >= REFIND_AFTER_S:
            link = self._refind(name, link)
        self._touch(name)
        return PracticeRobot(name, owner_id, username, link, token)

    def _read_row(self, where) -> _Row | None:
        with self._sessions() as session:
            record = session.scalar(select(PersonalRobotRecord).where(where))
            if record is None or not record.address:
                return None
            return _Row(record.name, record.owner_id, record.owner_name, record.token, record.address)

    def _link(self, name: str, address: str) -> RobotLink:
        with self._lock:
            link = self._links.get(name)
            if link is not None and link.address == address:
                return link
            self._links[name] = RobotLink(name, address, self._rpc_timeout_s)
        if link is not None:
            link.close()
        return self._links[name]

    def _refind(self, name: str, link: RobotLink) -> RobotLink:
        """Asks the farm where a robot that stopped answering is now (a restart may have moved it)."""
        now = time.monotonic()
        if now - self._refound_at.get(name, -1e9) < REFIND_AFTER_S:
            return link
        self._refound_at[name] = now
        try:
            robot = self.farm.find(name)
        except FarmUnavailable:
            return link
        if robot is None or robot.address == link.address:
            return link
        with self._lock:  # the keeper writes it (a request's lookup writes nothing of its own)
            self._moved[name] = (self._moved.get(name, (link.address, ""))[0], robot.address)
        return self._link(name, robot.address)

    def _touch(self, name: str) -> None:
        """Notes a use of the robot called name; the keeper writes it (a request's lookup writes nothing)."""
        with self._lock:
            self._used_at[name] = self._clock()

    def write_noted(self) -> None:
        """Writes the uses and moves this process noted since it last did, in a unit of work of its own: the
        keeper's duty (every few seconds, and before it looks for idle robots), never a request's."""
        with self._lock:
            uses, self._used_at = self._used_at, {}
            moves = dict(self._moved)  # kept until written: lookups meanwhile still go where the robot is now
        if not uses and not moves:
            return
        with self._sessions() as session, session.begin():
            for name, used_at in uses.items():  # a newer use, written by another worker meanwhile, stays
                session.execute(update(PersonalRobotRecord).where(PersonalRobotRecord.name == name,
                                                                  PersonalRobotRecord.last_used_at < used_at)
                                .values(last_used_at=used_at))
            for name, (was, now) in moves.items():
                session.execute(update(PersonalRobotRecord).where(PersonalRobotRecord.name == name,
                                                                  PersonalRobotRecord.address == was)
                                .values(address=now))
                announce_change(session, name)
        with self._lock:
            for name, move in moves.items():
                if self._moved.get(name) == move:
                    del self._moved[name]
        for name in moves:
            self._rows.drop(name)

    def scene_of(self, name: str) -> str | None:
        """The scene the practice robot called name runs."""
        with self._sessions() as session:
            return session.scalar(select(PersonalRobotRecord.scene).where(PersonalRobotRecord.name == name))

    def _release(self, name: str, token: str | None = None) -> None:
        with self._sessions() as session, session.begin():
            session.execute(delete(PersonalRobotRecord).where(
                PersonalRobotRecord.name == name, *([PersonalRobotRecord.token == token] if token else [])))
            announce_change(session, name)
        self._rows.drop(name)

    def _forget(self, name: str) -> None:
        self._rows.drop(name)
        with self._lock:
            link = self._links.pop(name, None)
            self._used_at.pop(name, None)
            self._moved.pop(name, None)
        if link is not None:
            link.close()

    def _keep_forever(self) -> None:
        interval_s = min(10.0, max(0.5, self.idle_s / 4))
        while not self._stop.wait(interval_s):
            try:
                self.release_dead_starts()
                self.stop_idle()
            except Exception:  # noqa: BLE001 - one failed stop must not end the keeper
                log.exception("stopping idle practice robots failed")



_managers: weakref.WeakSet[PracticeManager] = weakref.WeakSet()


def _close_all_at_exit() -> None:
    for manager in _managers:
        manager.close()


def init_app(app: Flask, registry: RobotRegistry, farm: RobotFarm) -> None:
    """Creates app's manager over farm, from TELELAB_PRACTICE_CAP / TELELAB_PRACTICE_IDLE_S (or PRACTICE_*)."""
    cap, idle_s = read_limits()
    cap = app.config.get("PRACTICE_CAP", cap)
    manager = PracticeManager(farm, session_factory(app), float(app.config.get("PRACTICE_IDLE_S", idle_s)),
                              None if cap is None else int(cap), float(app.config["ROBOT_RPC_TIMEOUT_S"]))
    app.extensions[_EXTENSION_KEY] = manager
    registry.set_personal(PRACTICE_PREFIX, manager.personal_robot)
    if not _managers:
        atexit.register(_close_all_at_exit)
    _managers.add(manager)
    try:
        manager.forget_lost()
        if manager.count():  # robots left running by an earlier process (the Ray farm's): reap them when idle
            manager.start_keeper()
    except (FarmUnavailable, DBAPIError) as error:  # no table yet (before `telelab db upgrade`), or farm away
        log.info("practice robots not checked at start: %s", error.__class__.__name__)


def practice_manager(app: Flask | None = None) -> PracticeManager:
    """The practice manager of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
