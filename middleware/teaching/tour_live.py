"""Live guided sessions: the state every page shows, and the channel that pushes it when the tutor acts.

A change is announced on the event bus (topic "tours", the session's id; middleware/events.py), which wakes the
sockets of that session in every worker process at once; a socket reads the session from the database only when
woken so, or each second while this process cannot hear announcements (its PostgreSQL listener reconnecting).
Who is present is a table every worker shares: a row per open page, refreshed while its socket lives and
deleted when it closes; a worker that died leaves rows that stop counting once PRESENCE_FRESH_S old.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import socket
import threading
import time
from collections.abc import Callable
from datetime import UTC, datetime, timedelta

from flask import current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy import delete, select, update
from sqlalchemy.orm import Session

from middleware import events
from middleware.db import get_session, unit_of_work
from middleware.live.loop import Continuation, blocking_work
from middleware.live.wire import LiveSocket
from middleware.models import User
from middleware.models.teaching import GuidedSession, GuidedSessionPresence, Tour
from middleware.realtime import CLOSE_FORBIDDEN, CLOSE_NOT_FOUND, Channels, WebSocket, as_json, refuse
from middleware.teaching.authority import may_follow_class
from middleware.teaching.tours import tour_steps
from middleware.validation import decimal_int

_changed = threading.Condition()
_versions: dict[int, int] = {}
_wakers: dict[int, set[Callable[[], None]]] = {}  # session id -> how to wake each of its sockets
RECHECK_S = 1.0  # how often a socket checks that it is still open (and re-reads, if announcements go unheard)
PRESENCE_REFRESH_S = 20.0
PRESENCE_FRESH_S = 60.0  # a page not heard of for this long (its worker died) no longer counts as present
TOPIC = "tours"
_listening_engines: set[int] = set()


def notify(session_id: int) -> None:
    """Wakes the sockets of session_id."""
    with _changed:
        _versions[session_id] = _versions.get(session_id, 0) + 1
        _changed.notify_all()
        wakers = list(_wakers.get(session_id, ()))
    for wake in wakers:
        wake()


def announce(session: Session, session_id: int) -> None:
    """Announces a change of the class, heard by every worker's sockets once session commits."""
    events.announce(session, TOPIC, str(session_id))


def _heard(key: str | None) -> None:
    if key is None:  # the listener reconnected: anything may have changed
        for session_id in list(_versions):
            notify(session_id)
    elif (heard_id := decimal_int(key, 1)) is not None:
        notify(heard_id)


def _bus_for(db: Session) -> events.EventBus:
    engine = db.get_bind().engine
    bus = events.bus_of(engine)
    if id(engine) not in _listening_engines:
        _listening_engines.add(id(engine))
        bus.listen(TOPIC, _heard)
    return bus


def state(session: Session, live: GuidedSession) -> dict[str, object]:
    """What every page of the class shows."""
    tour = session.get(Tour, live.tour_id)
    steps = tour_steps(tour) if tour is not None else []
    controller = session.get(User, live.control_user_id) if live.control_user_id else None
    tutor = session.get(User, live.tutor_id)
    step = steps[live.step_index].to_dict() if 0 <= live.step_index < len(steps) else None
    return {
        "type": "state", "id": live.id, "tour_id": live.tour_id, "robot": live.robot_name,
        "tutor": tutor.username if tutor else None, "step_index": live.step_index, "step_count": len(steps),
        "step": step, "controller": controller.username if controller else None,
        "ended": live.ended_at is not None, "version": live.version,
        "participants": present_names(session, live.id),
    }


def present_names(session: Session, session_id: int) -> list[str]:
    """The users with a page of the class open now, in any worker."""
    fresh_after = datetime.now(UTC) - timedelta(seconds=PRESENCE_FRESH_S)
    return list(session.scalars(
        select(User.username).distinct()
        .join(GuidedSessionPresence, GuidedSessionPresence.user_id == User.id)
        .where(GuidedSessionPresence.session_id == session_id, GuidedSessionPresence.heard_at > fresh_after)
        .order_by(User.username)))


def _arrive(session_id: int, user_id: int, socket_key: str) -> None:
    with unit_of_work(current_app) as db:
        db.add(GuidedSessionPresence(session_id=session_id, user_id=user_id, socket_key=socket_key))
        announce(db, session_id)  # the tutor's list of participants changes, in every worker


def _still_here(socket_key: str) -> None:
    with unit_of_work(current_app) as db:
        db.execute(update(GuidedSessionPresence).where(GuidedSessionPresence.socket_key == socket_key)
                   .values(heard_at=datetime.now(UTC)))


def _leave(session_id: int, socket_key: str) -> None:
    with unit_of_work(current_app) as db:
        db.execute(delete(GuidedSessionPresence).where(GuidedSessionPresence.socket_key == socket_key))
        announce(db, session_id)


def _read_state(session_id: int) -> dict[str, object] | None:
    db = get_session()
    try:
        live = db.get(GuidedSession, session_id)
        return None if live is None else state(db, live)
    finally:
        db.close()  # a socket lives long: no transaction stays open between reads


def session_channel(ws: WebSocket, session_id: int) -> Continuation | None:
    """Pushes the class's state whenever it changes, until the socket closes."""
    user_id = int(current_user.get_id())
    db = get_session()
    found = db.get(GuidedSession, session_id)
    if found is None:
        refuse(ws, CLOSE_NOT_FOUND, "unknown_session", gettext("There is no such class."))
        return None
    follower = db.get(User, user_id)
    if follower is None or not may_follow_class(db, follower, found):
        refuse(ws, CLOSE_FORBIDDEN, "not_in_course", gettext("This class is for the students of another course."),
               "session_id")
        return None
    bus = _bus_for(db)
    work = blocking_work()

    async def follow(live: LiveSocket) -> None:
        loop = asyncio.get_running_loop()
        socket_key = f"{socket.gethostname()[:60]}:{os.getpid()}:{id(live)}"

        def wake() -> None:
            with contextlib.suppress(RuntimeError):  # the loop closed: the process is ending
                loop.call_soon_threadsafe(live.nudge)

        with _changed:
            _wakers.setdefault(session_id, set()).add(wake)
        await work(_arrive, session_id, user_id, socket_key)
        refreshed_at = time.monotonic()
        sent: tuple[int, tuple[object, ...]] | None = None
        seen_local, read_local = -1, -2
        try:
            while live.connected:
                hears = not bus.shared or bus.listening.is_set()
                if seen_local != read_local or not hears:
                    read_local = seen_local
                    current = await work(_read_state, session_id)
                    if current is None:
                        break
                    participants = current["participants"]
                    signature = (int(current["version"]),
                                 tuple(participants) if isinstance(participants, list) else ())
                    if signature != sent:
                        await live.send(as_json(current))
                        sent = signature
                if _versions.get(session_id, 0) == read_local:
                    await live.receive(timeout=RECHECK_S)  # woken by notify(); what the page sends is dropped
                seen_local = _versions.get(session_id, 0)
                if time.monotonic() - refreshed_at >= PRESENCE_REFRESH_S:
                    await work(_still_here, socket_key)
                    refreshed_at = time.monotonic()
        finally:
            with _changed:
                _wakers.get(session_id, set()).discard(wake)
            await work(_leave, session_id, socket_key)

    return follow


def register(sock: Channels) -> None:
    """Declares the class channel."""
    sock.route("/ws/tour-sessions/<int:session_id>", endpoint="tour_session_channel")(session_channel)
