"""While a student's obstacle-zone test is in progress, nothing the middleware sends them shows the scene's obstacles
(issue 16): the exercise is to find them from accumulated sonar and laser readings. This module is the rule's one
owner; the lab's routes and channels ask it.

The rule holds for that student on every robot (another lab robot or their practice robot may run the same scene)
from the attempt's start until it ends (submitted, or its deadline passed). Walls stay (obstacle_zone.WALL_PREFIX):
the room's edge is not the exercise. Tutors, admins and other students are not concerned.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

from flask import Flask
from sqlalchemy import or_, select
from sqlalchemy.orm import Session

from middleware import events
from middleware.assessment.obstacle_zone import TASK_KIND, is_wall
from middleware.db import session_factory
from middleware.i18n import N_
from middleware.models.accounts import as_utc
from middleware.models.assessment import Attempt, Exam

OBSTACLES_HIDDEN = "obstacles_hidden"  # the stable code of every refusal and the scene's field naming the rule
HIDDEN_NOTE = ("Obstacles hidden during your obstacle-zone test: find them from the sonar and laser readings. "
               "They come back when you submit.")
CAMERA_REFUSAL = N_("No camera during your obstacle-zone test: the picture would show the obstacles. Find them from "
                    "the sonar and laser readings; the camera comes back when you submit.")
MAP_REFUSAL = N_("No map during your obstacle-zone test: a map can hold the lab's floor plan. Find the obstacles "
                 "from the sonar and laser readings; the map comes back when you submit.")
HIDDEN_VERSION_SUFFIX = "-obstacles-hidden"  # a scene version (its ETag) of its own: a cached full one is not reused


TOPIC = "obstacle-zone"  # announced when such an attempt starts or ends: every process reads the rule again at once
RECHECK_S = 2.0  # and otherwise at most this often (a missed announcement, a listener reconnecting)
_EXTENSION_KEY = "telelab.hidden_obstacles"


def users_hiding_obstacles(session: Session, now: datetime, user_id: int | None = None) -> dict[int, datetime | None]:
    """The users (or only user_id) with an obstacle-zone attempt in progress now (on any robot), each with the
    attempt's deadline (None: none)."""
    query = select(Attempt.user_id, Attempt.deadline_at, Exam.task).join(Exam, Attempt.exam_id == Exam.id).where(
        Attempt.status == "in_progress", Exam.kind == "experimental",
        or_(Attempt.deadline_at.is_(None), Attempt.deadline_at > now))
    if user_id is not None:
        query = query.where(Attempt.user_id == user_id)
    return {user: None if deadline is None else as_utc(deadline) for user, deadline, task in session.execute(query)
            if isinstance(task, dict) and task.get("kind") == TASK_KIND}


def hides_obstacles(session: Session, user_id: int, now: datetime) -> bool:
    """Whether user_id has an obstacle-zone attempt in progress now: then they see no obstacles."""
    return user_id in users_hiding_obstacles(session, now, user_id)


def announce_change(session: Session, user_id: int) -> None:
    """user_id's obstacle-zone attempt starts or ends in session's transaction: every process hears it when it
    commits, and asks the table again at its next question."""
    events.announce(session, TOPIC, str(user_id))


class HidingBook:
    """This process's copy of who hides obstacles now, for the paths a page polls or a camera re-checks: one read
    for everyone at most every RECHECK_S, and at once after an attempt's start or end is announced (any worker); a
    deadline passing counts at once, from the deadline read. Pages poll the robot's description every second: a
    read per poll halved what one web worker could serve (375 -> 200 users at p99 <= 100 ms)."""

    def __init__(self, sessions: Callable[[], Session], recheck_s: float = RECHECK_S) -> None:
        self._sessions, self._recheck_s = sessions, recheck_s
        self._lock = threading.Lock()
        self._users: dict[int, datetime | None] = {}
        self._read_at = -float("inf")

    def hides(self, user_id: int, session: Session | None = None) -> bool:
        """Whether user_id's obstacle-zone test is in progress: "no" as read at most RECHECK_S ago, "yes" read now
        for that user alone (a student who submits and reloads at once must not be refused by a reading older than
        the announcement of the end; only students in a test pay the read). session: the caller's (a request's), so
        that the read takes no second connection; no lock is held while it reads, so a pool that is busy never
        waits on this book."""
        now = datetime.now(UTC)
        with self._lock:
            due = time.monotonic() - self._read_at >= self._recheck_s
            if due:
                self._read_at = time.monotonic()  # this thread reads; the others go on with the last reading
        if due:
            try:
                users = self._read(session, now)
            except Exception:
                with self._lock:
                    self._read_at = -float("inf")  # the next question reads again
                raise
            with self._lock:
                self._users = users
        users = self._users
        if user_id not in users:
            return False
        deadline = users[user_id]
        if deadline is not None and deadline <= now:
            return False
        if due or user_id in self._read(session, now, user_id):
            return True
        self.forget()  # it ended and the announcement has not come yet: everyone's reading is as old
        return False

    def _read(self, session: Session | None, now: datetime, user_id: int | None = None) -> dict[int, datetime | None]:
        if session is not None:
            return users_hiding_obstacles(session, now, user_id)
        with self._sessions() as own:
            return users_hiding_obstacles(own, now, user_id)

    def forget(self, _key: str | None = None) -> None:
        """The next question reads the table again (an attempt started or ended somewhere)."""
        with self._lock:
            self._read_at = -float("inf")


def hiding_book(app: Flask) -> HidingBook:
    """app's book, made (and listening for starts) at the first question."""
    book = app.extensions.get(_EXTENSION_KEY)
    if book is None:
        factory = session_factory(app)
        made = HidingBook(factory)
        book = app.extensions.setdefault(_EXTENSION_KEY, made)
        if book is made:  # the first to ask (another thread may have made one first: then it listens)
            events.listen(factory.kw["bind"], TOPIC, book.forget)
    return book


def scene_without_obstacles(scene: dict[str, Any]) -> dict[str, Any]:
    """The scene route's answer with only the walls among its blocks and cylinders, saying so in `obstacles_hidden`."""
    return {**scene, "version": f"{scene.get('version', '')}{HIDDEN_VERSION_SUFFIX}",
            "blocks": [block for block in scene.get("blocks", []) if is_wall(str(block.get("name", "")))],
            "cylinders": [cylinder for cylinder in scene.get("cylinders", [])
                          if is_wall(str(cylinder.get("name", "")))],
            OBSTACLES_HIDDEN: HIDDEN_NOTE}


def info_without_obstacles(info: dict[str, Any]) -> dict[str, Any]:
    """The robot's description with only the walls among its scene boxes, saying so in `obstacles_hidden`."""
    return {**info, "scene_boxes": [box for box in info.get("scene_boxes", []) if is_wall(str(box.get("name", "")))],
            OBSTACLES_HIDDEN: HIDDEN_NOTE}
