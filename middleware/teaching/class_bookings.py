"""Class sessions attached to class bookings: a tutor's class booking opens the course's class session when its
slot starts (the robots start a few minutes before, so the class finds them ready) and ends it when the slot ends
or the booking is cancelled. One process of the cluster does it (an advisory lock elects it on PostgreSQL).

A session the tutor ended early is not opened again for the same booking; a session opened by hand is left
alone. A booking whose session cannot open (no students, a full or unreachable farm) is logged and tried again at
the next pass.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from datetime import datetime, timedelta

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.errors import Refused
from middleware.locking import ClusterElection
from middleware.models import Booking, User
from middleware.models.accounts import as_utc, utc_now
from middleware.models.farm import ClassSession
from middleware.teaching import class_sessions
from middleware.teaching.practice_robots import PracticeManager

log = logging.getLogger(__name__)
START_AHEAD = timedelta(minutes=5)
CHECK_EVERY_S = 15.0
CLASS_BOOKINGS_LOCK = 0x7E1E_C1A5


def sync_with_bookings(sessions: Callable[[], Session], manager: PracticeManager,
                       now: datetime | None = None) -> tuple[list[int], list[int]]:
    """Opens the class sessions of class bookings whose slot starts within START_AHEAD (or has started), and ends
    those whose booking ended or was cancelled; (bookings opened, sessions ended). Each booking is a unit of work
    of its own: one that is refused leaves the others' done."""
    now = now or utc_now()
    with sessions() as session:
        due = session.scalars(select(Booking.id).where(
            Booking.kind == "class", Booking.course_id.is_not(None), Booking.cancelled_at.is_(None),
            Booking.starts_at <= now + START_AHEAD, Booking.ends_at > now)).all()
    opened = [booking_id for booking_id in due if _open_for_booking(sessions, manager, booking_id)]
    return opened, _end_finished(sessions, manager, now)


def _open_for_booking(sessions: Callable[[], Session], manager: PracticeManager, booking_id: int) -> bool:
    """Opens the booking's class session unless it has one or its course has an open one; its robots start once
    it is committed. False when nothing was opened."""
    try:
        with sessions() as session, session.begin():
            booking = session.get(Booking, booking_id)
            if booking is None or booking.course_id is None:
                return False
            if (session.scalar(select(ClassSession.id).where(ClassSession.booking_id == booking.id)) is not None
                    or class_sessions.open_session(session, booking.course_id) is not None):
                return False
            tutor = session.get(User, booking.user_id)
            if tutor is None:
                return False
            started_id = class_sessions.start_session(session, tutor, booking.course_id, manager,
                                                      booking_id=booking.id).id
    except Refused as refusal:
        log.warning("the class booking %s did not open its session: %s", booking_id, refusal.message)
        return False
    class_sessions.prestart_robots(sessions, manager, started_id)
    return True


def _end_finished(sessions: Callable[[], Session], manager: PracticeManager, now: datetime) -> list[int]:
    with sessions() as session:
        rows = session.execute(select(ClassSession.id, ClassSession.course_id, Booking.id, Booking.user_id,
                                      Booking.cancelled_at, Booking.ends_at)
                               .join(Booking, Booking.id == ClassSession.booking_id)
                               .where(ClassSession.ended_at.is_(None))).all()
    ended = []
    for class_session_id, course_id, booking_id, tutor_id, cancelled_at, ends_at in rows:
        if cancelled_at is None and as_utc(ends_at) > now:
            continue
        try:
            with sessions() as session, session.begin():
                tutor = session.get(User, tutor_id)
                owners = None if tutor is None else class_sessions.end_session(session, tutor, course_id)
        except Refused as refusal:  # the booker no longer teaches the course: a tutor ends it by hand
            log.warning("the class session %s of booking %s was not ended: %s", class_session_id, booking_id,
                        refusal.message)
            continue
        if owners is None:
            continue
        for owner_id in owners:
            manager.stop(owner_id)
        ended.append(class_session_id)
    return ended


def any_class_booking_ahead(sessions: Callable[[], Session]) -> bool:
    """Whether a class booking has yet to end (the keeper is needed)."""
    with sessions() as session:
        return session.scalar(select(Booking.id).where(Booking.kind == "class", Booking.cancelled_at.is_(None),
                                                       Booking.ends_at > utc_now()).limit(1)) is not None


class ClassBookingKeeper:
    """The thread that keeps class sessions in step with class bookings, in the elected process."""

    def __init__(self, sessions: Callable[[], Session], manager: PracticeManager) -> None:
        self._sessions, self._manager = sessions, manager
        self._election = ClusterElection(sessions.kw["bind"], CLASS_BOOKINGS_LOCK)  # type: ignore[attr-defined]
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()

    def start(self) -> None:
        """Starts the thread once."""
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._keep_forever, name="class-bookings", daemon=True)
                self._thread.start()

    def _keep_forever(self) -> None:
        while not self._stop.wait(CHECK_EVERY_S):
            try:
                if self._election.leads():
                    sync_with_bookings(self._sessions, self._manager)
            except Exception:  # noqa: BLE001 - one failed pass must not end the keeper
                log.exception("keeping class sessions in step with class bookings failed")
