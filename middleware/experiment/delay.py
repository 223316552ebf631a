"""Injected video delay: every stream that shows one viewer where the robot is (camera, telemetry, localization)
held until capture time + delay, or arrival + delay for a stream without a capture time; and, during a trial whose
course's protocol says so, the student's drive commands too (`command_hold`, the drive channel's hook).

The thesis added delay with a distant proxy; here the relay does it per viewer. `DelayQueue` is the pure
part (ordering, bounds); `parse_delay_s` validates a requested delay; `ViewerDelay` follows one viewer's
delay on one robot through the process's `DelayBook`, which reads every delay in force from the database (so
every worker process applies it) in one query, again only after a change is announced on the event bus (topic
"delays", by any worker; middleware/events.py), or at most every REFRESH_S while announcements cannot be heard.

Two kinds of delay are in force: a tutor's (`video_delays`, on every robot the user watches) and an open
experiment trial's (its own row in `experiment_trials`, on the trial's robot only, for as long as the trial is
open). On the trial's robot the trial's delay wins: it is the condition being measured.
"""

from __future__ import annotations

import json
import math
import struct
import threading
import time
from collections import deque
from collections.abc import Callable

from flask import current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import String, literal, select, union_all

from middleware import events
from middleware.auth.schemas import InvalidField
from middleware.db import session_factory
from middleware.errors import written_number
from middleware.models.experiment import MAX_INJECTED_DELAY_S, TRIAL_OPEN, Trial, VideoDelay

DEFAULT_MAX_MESSAGES = 600  # 7 s of 20 Hz telemetry or 30 fps video, with room to spare
DEFAULT_MAX_BYTES = 32 * 1024 * 1024
REFRESH_S = 1.0
_BOOK_KEY = "telelab.delay_book"

# (user id, robot name) -> delay [s]; robot name None: a tutor's delay, on every robot.
Delays = dict[tuple[int, str | None], float]


def parse_delay_s(value: object, field: str = "delay_s") -> float:
    """A delay in seconds, 0 to 7; anything else (negative, absurd, NaN, text, bool) is refused naming field."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InvalidField(field, gettext("%(field)s must be a number of seconds from 0 to %(high)s.", field=field,
                                          high=written_number(MAX_INJECTED_DELAY_S, "g")))
    delay = float(value)
    if not math.isfinite(delay) or delay < 0 or delay > MAX_INJECTED_DELAY_S:
        raise InvalidField(field, gettext("%(field)s must be from 0 to %(high)s seconds.", field=field,
                                          high=written_number(MAX_INJECTED_DELAY_S, "g")))
    return round(delay, 3)


def capture_time_s(message: bytes | str) -> float | None:
    """The capture_unix_s of a packed camera (bytes) or telemetry (JSON text) message, if it has one."""
    try:
        if isinstance(message, bytes | bytearray):
            (length,) = struct.unpack(">I", message[:4])
            header = json.loads(message[4 : 4 + length])
        else:
            header = json.loads(message)
    except (ValueError, struct.error, TypeError):
        return None
    value = header.get("capture_unix_s") if isinstance(header, dict) else None
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else None


class DelayQueue:
    """Messages held until their release time, in arrival order; bounded in count and bytes (oldest dropped)."""

    def __init__(self, delay_s: float, max_messages: int = DEFAULT_MAX_MESSAGES, max_bytes: int = DEFAULT_MAX_BYTES):
        self.delay_s = parse_delay_s(delay_s)
        if max_messages < 1 or max_bytes < 1:
            raise ValueError("a delay queue holds at least one message")
        self._max_messages, self._max_bytes = max_messages, max_bytes
        self._held: deque[tuple[float, bytes | str]] = deque()
        self._bytes = 0
        self.dropped = 0

    def __len__(self) -> int:
        return len(self._held)

    @property
    def held_bytes(self) -> int:
        """Bytes currently held."""
        return self._bytes

    def push(self, message: bytes | str, capture_s: float | None, now_s: float) -> None:
        """Holds message until capture_s + delay (never before now_s, and never before an earlier message)."""
        release = max(now_s, (capture_s if capture_s is not None else now_s) + self.delay_s)
        if self._held and release < self._held[-1][0]:
            release = self._held[-1][0]  # keep arrival order even if the robot's clock stepped back
        self._held.append((release, message))
        self._bytes += len(message)
        while len(self._held) > self._max_messages or (self._bytes > self._max_bytes and len(self._held) > 1):
            _, old = self._held.popleft()
            self._bytes -= len(old)
            self.dropped += 1

    def pop_due(self, now_s: float) -> list[bytes | str]:
        """The messages whose time has come, oldest first."""
        due: list[bytes | str] = []
        while self._held and self._held[0][0] <= now_s:
            _, message = self._held.popleft()
            self._bytes -= len(message)
            due.append(message)
        return due

    def seconds_until_next(self, now_s: float) -> float | None:
        """How long until the next release, or None when nothing is held."""
        return max(0.0, self._held[0][0] - now_s) if self._held else None

    def set_delay(self, delay_s: float) -> None:
        """Changes the delay for messages pushed from now on (held ones keep their time)."""
        self.delay_s = parse_delay_s(delay_s)


class ViewerDelay:
    """One viewer's delay, re-read through read_delay_s() at most every refresh_s."""

    def __init__(self, read_delay_s: Callable[[], float], refresh_s: float = REFRESH_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._read, self._refresh_s, self._clock = read_delay_s, refresh_s, clock
        self._value = 0.0
        self._read_at = float("-inf")

    def current(self) -> tuple[float, bool]:
        """(delay_s, changed since the last call that read it)."""
        now = self._clock()
        if now - self._read_at < self._refresh_s:
            return self._value, False
        self._read_at = now
        try:
            value = float(self._read())
        except Exception:  # noqa: BLE001 - a database hiccup keeps the last known delay
            return self._value, False
        changed = value != self._value
        self._value = value
        return value, changed


def delay_in_force_s(delays: Delays, user_id: int, robot_name: str) -> float:
    """user_id's delay on robot_name: an open trial's on that robot, else a tutor's, else 0."""
    trial_delay = delays.get((user_id, robot_name))
    return trial_delay if trial_delay is not None else delays.get((user_id, None), 0.0)


class DelayBook:
    """Every injected delay in force in this process, read in one query at most every refresh_s.

    Each viewer asked the database for its own delay every second: with 100 viewers that was 100 queries a
    second and a fifth of the middleware's time under the capacity load. One shared read costs one query.
    A failed read keeps the last known delays until the next period.
    """

    def __init__(self, load: Callable[[], Delays], refresh_s: float = REFRESH_S,
                 clock: Callable[[], float] = time.monotonic,
                 hears_changes: Callable[[], bool] = lambda: False,
                 load_commands: Callable[[], Delays] = dict) -> None:
        self._load, self._refresh_s, self._clock = load, refresh_s, clock
        self._load_commands = load_commands
        self._hears_changes = hears_changes  # True: changes are announced (forget), so no periodic read
        self._delays: Delays = {}
        self._command_delays: Delays = {}
        self._loaded_at = float("-inf")
        self._lock = threading.Lock()

    def delay_of(self, user_id: int, robot_name: str) -> float:
        """user_id's delay on robot_name as read at most refresh_s ago (0 when none is in force)."""
        self._read_if_due()
        return delay_in_force_s(self._delays, user_id, robot_name)

    def command_delay_of(self, user_id: int, robot_name: str) -> float:
        """The delay on user_id's commands to robot_name: their open trial's there when its course's protocol
        delays commands (the distant proxy), else 0."""
        self._read_if_due()
        return self._command_delays.get((user_id, robot_name), 0.0)

    def _read_if_due(self) -> None:
        period = float("inf") if self._hears_changes() else self._refresh_s
        if self._clock() - self._loaded_at >= period:
            with self._lock:
                if self._clock() - self._loaded_at >= period:
                    try:
                        self._delays = self._load()
                        self._command_delays = self._load_commands()
                    finally:
                        self._loaded_at = self._clock()  # after a failure too: not one retry per viewer

    def forget(self) -> None:
        """The next read goes to the database (a delay was just changed in this process)."""
        self._loaded_at = float("-inf")


def read_all_delays_s(session) -> Delays:
    """Every delay in force: tutors' (robot name None) and open trials' (on their robot)."""
    tutors = select(VideoDelay.user_id, literal(None, String).label("robot_name"), VideoDelay.delay_s)
    trials = select(Trial.user_id, Trial.robot_name, Trial.delay_s).where(Trial.status == TRIAL_OPEN)
    return {(user_id, robot_name): float(delay_s)
            for user_id, robot_name, delay_s in session.execute(union_all(tutors, trials))}


def read_command_delays_s(session) -> Delays:
    """The open trials that hold their student's commands too, by (user, robot)."""
    rows = session.execute(select(Trial.user_id, Trial.robot_name, Trial.delay_s)
                           .where(Trial.status == TRIAL_OPEN, Trial.commands_delayed.is_(True)))
    return {(user_id, robot_name): float(delay_s) for user_id, robot_name, delay_s in rows}


def delay_book(app=None) -> DelayBook:
    """The delay book of app (or of the current app), made on first use."""
    app = app or current_app._get_current_object()  # type: ignore[attr-defined]
    book = app.extensions.get(_BOOK_KEY)
    if book is None:
        factory = session_factory(app)

        def load() -> Delays:
            with factory() as session:
                return read_all_delays_s(session)

        def load_commands() -> Delays:
            with factory() as session:
                return read_command_delays_s(session)

        bus = events.bus_of(factory.kw["bind"])
        made = DelayBook(load, hears_changes=lambda: not bus.shared or bus.listening.is_set(),
                         load_commands=load_commands)
        book = app.extensions.setdefault(_BOOK_KEY, made)
        if book is made:
            bus.listen("delays", lambda _user: made.forget())
    return book


def viewer_hold(robot_name: str, user_id: int) -> ViewerHold:
    """user_id's hold on a stream of robot_name, by the process's delay book (realtime.relay_stream's hook,
    composed in create_app)."""
    book = delay_book()
    return ViewerHold(ViewerDelay(lambda: book.delay_of(user_id, robot_name), refresh_s=0.0))  # the book limits reads


def command_hold(robot_name: str, user_id: int) -> Callable[[], float]:
    """How long user_id's commands to robot_name are held now, by the process's delay book (the drive channel's
    hook, composed in create_app). It may read the database: call it off the channel loop."""
    book = delay_book()
    return lambda: book.command_delay_of(user_id, robot_name)


def apply_viewer_delay(ws, delay: ViewerDelay | None, held: DelayQueue, online: bool = True) -> float:
    """The viewer's delay now; a change is applied to held and announced on the socket (with the robot's status)."""
    if delay is None:
        return 0.0
    value, changed = delay.current()
    if changed:
        held.set_delay(value)
        ws.send(json.dumps({"type": "status", "robot_online": online, "injected_delay_s": value,
                            "message": f"An added delay of {value:g} s is on your video." if value else ""},
                           separators=(",", ":")))
    return value


class ViewerHold:
    """One viewer's injected delay on one stream: the delay in force and the messages held back by it."""

    def __init__(self, delay: ViewerDelay) -> None:
        self._delay, self._held = delay, DelayQueue(0.0)

    def update(self, ws, online: bool) -> bool:
        """Reads the delay in force (a change is announced on ws); whether messages are held now (after a delay
        ends, the held ones go first)."""
        return apply_viewer_delay(ws, self._delay, self._held, online) > 0 or len(self._held) > 0

    def push(self, message: bytes | str, now_s: float) -> None:
        """Holds message until its capture time (or now_s) + the delay."""
        self._held.push(message, capture_time_s(message), now_s)

    def pop_due(self, now_s: float) -> list[bytes | str]:
        """The held messages whose time has come, oldest first."""
        return self._held.pop_due(now_s)

    def seconds_until_next(self, now_s: float) -> float | None:
        """How long until the next release, or None when nothing is held."""
        return self._held.seconds_until_next(now_s)
