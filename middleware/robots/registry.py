"""The robots this middleware process knows, one RobotLink each, following the robots table.

The table (managed by admins, seeded from TELELAB_ROBOTS) is re-read when a change to it is announced on the
event bus (middleware/events.py: by any process with PostgreSQL), and at once after a change made in this
process (`refresh(force=True)`). With SQLite, whose announcements stay in their process, it is also re-read at
most every `refresh_s` seconds when someone asks (a `telelab` command beside the server may have changed it).
Disabled robots have no link: `get()` answers None (so pages and sockets give 404s) and their old
link is closed. Until the table exists (before `telelab db upgrade`), the configuration is used.

Personal robots (the practice robots) are not in the table: names with the personal prefix are resolved
by the resolver their manager registers (`set_personal`). The registry is plumbing: it answers for every
robot and knows nothing of the logged-in user; who may reach a robot is decided by
`access.commands.RobotCommands.reachable(name, user_id)` (a personal robot: its owner only). Personal
robots are never listed in `names()`, and lab robots may not use the prefix.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from flask import Flask, current_app
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import Session

from middleware import events
from middleware.config import RobotAddress
from middleware.db import session_factory
from middleware.robots.catalog import RobotEntry, load_entries, seed_from_config
from middleware.robots.link import RobotLink

_EXTENSION_KEY = "telelab.robots"
DEFAULT_REFRESH_S = 3.0
ROBOTS_TOPIC = "robots"  # announced with a robot's name whenever the robots table changes
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PersonalRobot:
    """A robot that belongs to one user (a practice robot): its link, title, owner and the owner's token."""

    link: RobotLink
    title: str
    owner_id: int
    token: str


PersonalResolver = Callable[[str], PersonalRobot | None]


class RobotRegistry:
    """Links to every enabled robot, created once per process and replaced when the table changes."""

    def __init__(self, robots: tuple[RobotAddress, ...], rpc_timeout_s: float,
                 sessions: Callable[[], Session] | None = None, refresh_s: float = DEFAULT_REFRESH_S) -> None:
        self._configured = robots
        self._rpc_timeout_s = rpc_timeout_s
        self._sessions = sessions
        self._refresh_s = refresh_s
        self._seeded = sessions is None
        self._lock = threading.Lock()
        self._read_at = -float("inf")
        self._closed = False
        self._links: dict[str, RobotLink] = {}
        # Every robot ever seen (disabled ones too), so a title is always found for a name listed earlier.
        self._entries: dict[str, RobotEntry] = {}
        self._personal_prefix: str | None = None
        self._personal_resolver: PersonalResolver | None = None
        self._apply([RobotEntry(r.name, r.address, r.title) for r in robots])

    @property
    def addresses(self) -> dict[str, RobotEntry]:
        """name -> entry (address, title, enabled) of every robot known, including disabled ones."""
        self._maybe_refresh()
        return self._entries

    def get(self, name: str) -> RobotLink | None:
        """The link to the enabled robot (or running personal robot) called name, if there is one."""
        if self.is_personal_name(name):
            personal = self.personal(name)
            return None if personal is None else personal.link
        self._maybe_refresh()
        return self._links.get(name)

    def names(self) -> list[str]:
        """Every enabled lab robot's name, in the order they were added (personal robots are never listed)."""
        self._maybe_refresh()
        return [name for name in self._links if not self.is_personal_name(name)]

    def title(self, name: str) -> str | None:
        """The title to show for a robot that get() answers for now; None otherwise."""
        if self.is_personal_name(name):
            personal = self.personal(name)
            return None if personal is None else personal.title
        if self.get(name) is None:
            return None
        return self._entries[name].title

    def set_personal(self, prefix: str, resolver: PersonalResolver) -> None:
        """Names starting with prefix are personal robots, found by resolver (and hidden from everyone else)."""
        self._personal_prefix, self._personal_resolver = prefix, resolver

    def is_personal_name(self, name: str) -> bool:
        """Whether name is in the personal robots' namespace."""
        return self._personal_prefix is not None and name.startswith(self._personal_prefix)

    def personal(self, name: str) -> PersonalRobot | None:
        """The running personal robot called name, if there is one."""
        if self._personal_resolver is None or not self.is_personal_name(name):
            return None
        return self._personal_resolver(name)

    def owner_of(self, name: str) -> int | None:
        """The owner of the personal robot called name; None for a lab robot (or no robot)."""
        personal = self.personal(name)
        return None if personal is None else personal.owner_id

    def refresh(self, force: bool = True) -> None:
        """Re-reads the robots table now (force) or when the last read is older than refresh_s."""
        if self._sessions is None or self._closed:
            return
        with self._lock:
            if not force and time.monotonic() - self._read_at < self._refresh_s:
                return
            self._read_at = time.monotonic()
            try:
                with self._sessions() as session:
                    if not self._seeded:
                        seed_from_config(session, self._configured)
                        self._seeded = True
                    entries = load_entries(session)
            except DBAPIError as error:  # no robots table yet (database not migrated): keep what we have
                log.debug("robots table not readable (%s); using TELELAB_ROBOTS", error.__class__.__name__)
                return
            self._apply(entries)

    def close(self) -> None:
        """Closes every link (application shutdown, tests)."""
        self._closed = True
        for link in list(self._links.values()):
            link.close()

    def _maybe_refresh(self) -> None:
        if self._sessions is not None and time.monotonic() - self._read_at >= self._refresh_s:
            self.refresh(force=False)

    def _apply(self, entries: list[RobotEntry]) -> None:
        """Swaps in links for the enabled entries, closing links of robots disabled or moved."""
        links: dict[str, RobotLink] = {}
        stale: list[RobotLink] = []
        for entry in entries:
            old = self._links.get(entry.name)
            if not entry.enabled:
                continue
            if old is not None and self._entries.get(entry.name, entry).address == entry.address:
                links[entry.name] = old
            else:
                links[entry.name] = RobotLink(entry.name, entry.address, self._rpc_timeout_s)
        stale = [link for name, link in self._links.items() if links.get(name) is not link]
        self._entries = {**self._entries, **{e.name: e for e in entries}}
        self._links = links
        for link in stale:
            link.close()


def init_app(app: Flask) -> RobotRegistry:
    """Creates the registry for app from its ROBOTS setting and the robots table (seeded here)."""
    sessions = session_factory(app)
    bus = events.bus_of(sessions.kw["bind"])
    refresh_s = float("inf") if bus.shared else float(app.config.get("ROBOTS_REFRESH_S", DEFAULT_REFRESH_S))
    registry = RobotRegistry(app.config["ROBOTS"], app.config["ROBOT_RPC_TIMEOUT_S"], sessions, refresh_s)
    app.extensions[_EXTENSION_KEY] = registry
    bus.listen(ROBOTS_TOPIC, lambda _name: registry.refresh())
    registry.refresh()
    return registry


def robot_registry(app: Flask | None = None) -> RobotRegistry:
    """The registry of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
