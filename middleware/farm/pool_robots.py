"""A pool's simulated robots on the farm: started for a kind, recorded in the robots table (so every worker's
registry and the round-robin rule serve them like any lab robot), kept at their current address, and stopped.

A farm robot is a row with farm_managed set and the scene it runs; the keeper here makes the farm match the
rows: it follows a robot the farm restarted on a new port, and starts again a robot whose process went with
an earlier web server (the local farm's robots end with their process).
"""

from __future__ import annotations

import logging
import re
import threading
from collections.abc import Callable

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.exc import DBAPIError, IntegrityError
from sqlalchemy.orm import Session

from middleware import events
from middleware.errors import Refused
from middleware.farm.base import FarmUnavailable, RobotFarm, RobotSpec
from middleware.models import Robot
from middleware.models.accounts import utc_now
from middleware.robots.link import answers_at
from middleware.validation import InvalidInput, whole_number

log = logging.getLogger(__name__)
KEEP_EVERY_S = 2.0
MAX_POOL_START = 50
_SLUG = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,23}")
_SCENE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,63}")


def clean_pool_request(kind: object, scene: object, count: object) -> tuple[str, str, int]:
    """(kind, scene, count) of a request to start a pool's robots; InvalidInput names the field at fault."""
    if not isinstance(kind, str) or not _SLUG.fullmatch(kind.strip()):
        raise InvalidInput("kind", gettext("kind must be 1 to 24 letters, digits, '-' or '_' (the robots are named "
                                           "kind-1...)."))
    if not isinstance(scene, str) or not _SCENE.fullmatch(scene.strip()):
        raise InvalidInput("scene", gettext("scene must name a simulator scene such as 'lab' or 'course-A'."))
    return kind.strip(), scene.strip(), whole_number(count, "count", 1, MAX_POOL_START)


def start_pool_robots(farm: RobotFarm, session: Session, kind: str, scene: str, count: int) -> list[str]:
    """Starts count more simulated robots of kind on the farm, named kind-N after the names in use, and records each
    as an enabled lab robot of the kind in session (the caller's unit of work, which commits them). All or none: a
    refusal (the farm full or unreachable, an unknown scene, a name taken meanwhile) stops the robots this call
    started, and the caller's unit of work keeps no row."""
    taken = set(session.scalars(select(Robot.name)))
    other_kind = session.scalar(select(Robot.kind).where(Robot.kind == kind, Robot.farm_managed.is_(True),
                                                         Robot.scene != scene).limit(1))
    if other_kind is not None:
        raise Refused(409, "scene_mismatch", gettext("The farm's robots of kind %(kind)s run another scene; a kind is "
                                                     "one scene and model, so choose that scene or another kind.",
                                                     kind=repr(kind)), "scene")
    names: list[str] = []
    number = 0
    while len(names) < count:
        number += 1
        if f"{kind}-{number}" not in taken:
            names.append(f"{kind}-{number}")
    started: list[str] = []
    try:
        for name in names:
            robot = farm.start(RobotSpec(name, scene))
            started.append(name)
            session.add(Robot(name=name, title=f"{kind.capitalize()} {name.rsplit('-', 1)[1]}", address=robot.address,
                              kind=kind, farm_managed=True, scene=scene, enabled=True))
            events.announce(session, "robots", name)
        session.flush()
    except IntegrityError:  # another admin took a name meanwhile; the caller's unit of work rolls back
        stop_pool_processes(farm, started)
        raise Refused(409, "robot_exists", lazy_gettext("A robot of that name was added meanwhile; no robot was "
                                                       "started. Try again."), "kind") from None
    except BaseException:
        stop_pool_processes(farm, started)
        raise
    return started


def remove_pool_rows(session: Session, kind: str) -> list[str]:
    """Removes the rows of the farm's robots of kind in session (the caller's unit of work; robots the admin added
    by address stay); their names, whose robots stop_pool_processes ends once that is committed. The row goes first:
    a keeper never starts again a robot whose row is gone, where it did restart one stopped before its row went."""
    rows = list(session.scalars(select(Robot).where(Robot.kind == kind, Robot.farm_managed.is_(True))))
    if not rows:
        raise Refused(404, "unknown_pool", gettext("The farm runs no robots of kind %(kind)s.", kind=repr(kind[:32])),
                      "kind")
    for row in rows:
        session.delete(row)
        events.announce(session, "robots", row.name)
    session.flush()
    return [row.name for row in rows]


def stop_pool_processes(farm: RobotFarm, names: list[str]) -> None:
    """Stops the farm's robots whose rows remove_pool_rows removed (after the commit)."""
    for name in names:
        farm.stop(name)


def stop_pool_robots(farm: RobotFarm, sessions: Callable[[], Session], kind: str) -> list[str]:
    """Stops the farm's robots of kind in a unit of work of its own (the console's `telelab farm stop --pool`)."""
    with sessions() as session, session.begin():
        names = remove_pool_rows(session, kind)
    stop_pool_processes(farm, names)
    return names


def keep_pool_robots(farm: RobotFarm, sessions: Callable[[], Session]) -> list[str]:
    """Makes the farm match the rows: follows robots to a new address, starts again those running nowhere.

    A robot this process's farm does not know but that answers at its recorded address belongs to another
    process (the web server, while a `telelab` command runs) and is left alone. Returns the names changed."""
    with sessions() as session:
        rows = session.execute(select(Robot.name, Robot.address, Robot.scene)
                               .where(Robot.farm_managed.is_(True), Robot.enabled.is_(True))).all()
    changed = []
    for name, address, scene in rows:
        running = farm.find(name)
        if running is None:
            if answers_at(name, address):
                continue
            running = farm.start(RobotSpec(name, scene or "lab"))
        if running.address != address:
            with sessions() as session, session.begin():  # the keeper's own unit of work, one robot at a time
                row = session.scalar(select(Robot).where(Robot.name == name))
                if row is not None:
                    row.address, row.updated_at = running.address, utc_now()
                    events.announce(session, "robots", name)
            changed.append(name)
    return changed



class PoolKeeper:
    """The thread that keeps a process's pool robots running, started by the first process that serves them."""

    def __init__(self, farm: RobotFarm, sessions: Callable[[], Session], on_change: Callable[[], None]) -> None:
        self._farm, self._sessions, self._on_change = farm, sessions, on_change
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def start_if_needed(self) -> bool:
        """Starts the keeper when the table holds farm robots; True if it runs."""
        with self._lock:
            if self._thread is not None:
                return True
            try:
                with self._sessions() as session:
                    if session.scalar(select(Robot.id).where(Robot.farm_managed.is_(True)).limit(1)) is None:
                        return False
            except DBAPIError:
                return False  # no table yet (before `telelab db upgrade`)
            self._thread = threading.Thread(target=self._keep_forever, name="pool-keeper", daemon=True)
            self._thread.start()
            return True

    def keep_now(self) -> None:
        """One pass of the keeper, then the registry re-reads the table if an address changed."""
        if keep_pool_robots(self._farm, self._sessions):
            self._on_change()

    def stop(self) -> None:
        """Ends the thread (the robots stay with the farm)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5)

    def _keep_forever(self) -> None:
        while not self._stop.wait(KEEP_EVERY_S):
            try:
                self.keep_now()
            except (FarmUnavailable, DBAPIError) as error:
                log.warning("pool robots not kept this time: %s", error)
            except Exception:  # noqa: BLE001 - one failed pass must not end the keeper
                log.exception("keeping the pool robots failed")
