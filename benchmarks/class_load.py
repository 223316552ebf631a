"""The class-day benchmark's load on one asyncio loop: each student's console (one `/ws/link` with telemetry,
localization and drive at the console's rate, an ordinary request every second) and the tutor's wall (its page's
requests, then its channel), each reconnecting when its worker leaves (1012), and what each of them measured."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from benchmarks.load_client import HttpUser, Refused, WebSocketUser
from benchmarks.web_tier import log_in_one

DRIVE_INTERVAL_S = 0.05  # the console's rate (middleware/lab/sockets.py DRIVE_SEND_INTERVAL_MS)
REQUEST_INTERVAL_S = 1.0
SEAT_WAIT_S = 10.0  # a student who gets no acknowledgement this long after reconnecting has lost their seat
CHANNELS = ("telemetry", "localization", "drive")
DRIVE_SUB = 3
WALL_SUB = 1
WALL_WAIT_S = 30.0  # the class begins without the wall's floor if it showed nothing in this time


@dataclass
class Student:
    """One student's console, and what it measured."""

    name: str
    robot: str
    start_s: float
    acks_s: list[float] = field(default_factory=list)
    requests_s: list[float] = field(default_factory=list)
    request_errors: int = 0
    first_console_s: float | None = None
    reconnects_s: list[float] = field(default_factory=list)
    restarts_seen: int = 0
    seat_lost: bool = False
    in_at: float | None = None
    out_at: float | None = None
    telemetry: int = 0
    superseded: int = 0  # drive commands the server replaced by a newer one waiting behind them
    drives_sent: int = 0
    received: int = 0  # every message the console's link brought (stream messages, acks, the link's own)
    errors: list[str] = field(default_factory=list)

    @property
    def messages(self) -> int:
        """The messages this student's console exchanged: drive commands sent, messages received, requests."""
        return self.drives_sent + self.received + len(self.requests_s) + self.request_errors


@dataclass
class Wall:
    """The tutor's class wall, and what its channel brought."""

    course_id: int
    cookie: str
    received_at: list[float] = field(default_factory=list)  # each of its poses and seats messages [monotonic s]
    poses: int = 0
    seats: int = 0
    robots_shown: int = 0  # robots in its latest poses message
    shown_at: float | None = None  # its first poses message: the class on show [monotonic s]
    first_open_s: float | None = None
    reconnects_s: list[float] = field(default_factory=list)
    restarts_seen: int = 0
    left_at: float | None = None
    errors: list[str] = field(default_factory=list)

    def per_s(self, after: float, until: float) -> float | None:
        """Its messages a second after one moment until another."""
        if until <= after:
            return None
        return sum(after < at <= until for at in self.received_at) / (until - after)


class ClassLoad:
    """The class on one asyncio loop (this process): the tutor's wall from before the first login, and every student
    from their login to the end, length_s after the class began (or later: see end_at)."""

    def __init__(self, port: int, students: list[Student], wall: Wall, length_s: float) -> None:
        self.port, self.students, self.wall, self._length_s = port, students, wall, length_s
        self._end_at = float("inf")
        self.restart_done = False  # the class goes on until the restart is over, however long it takes
        self.began = threading.Event()  # set at the class's start (started), for the measuring thread
        self.started = 0.0

    @property
    def end_at(self) -> float:
        return self._end_at if self.restart_done else float("inf")

    @end_at.setter
    def end_at(self, value: float) -> None:
        self._end_at = value

    async def run(self, alone_s: float) -> None:
        """The wall opens first; once it shows the class (or WALL_WAIT_S passed) it stays alone for alone_s, its floor,
        and then the class begins: each student comes their start_s later."""
        wall = asyncio.ensure_future(self._wall())
        deadline = time.monotonic() + WALL_WAIT_S
        while self.wall.shown_at is None and not wall.done() and time.monotonic() < deadline:
            await asyncio.sleep(0.05)
        self.started = time.monotonic() + alone_s
        self._end_at = self.started + self._length_s
        self.began.set()
        await asyncio.gather(wall, *(self._student(s, self.started) for s in self.students))

    async def _student(self, student: Student, started: float) -> None:
        await asyncio.sleep(max(0.0, started + student.start_s - time.monotonic()))
        loop = asyncio.get_running_loop()
        try:
            cookie = await loop.run_in_executor(None, log_in_one, f"http://127.0.0.1:{self.port}", student.name)
        except Exception as error:  # noqa: BLE001 - reported: a login that failed is a student who never came in
            student.errors.append(f"login: {error}")
            return
        student.in_at = time.monotonic()
        requests = asyncio.ensure_future(self._requests(student, cookie))
        try:
            student.restarts_seen = await self._keep_link(
                cookie, student.errors, lambda link, opened, closed_at: self._console(student, link, opened, closed_at))
        finally:
            student.out_at = time.monotonic()
            requests.cancel()

    async def _keep_link(self, cookie: str, errors: list[str],
                         hold: Callable[[WebSocketUser, float, float | None], Awaitable[int]]) -> int:
        """A page's /ws/link until the class ends, opened again at once when its worker leaves (1012); hold(link,
        opened at, the last one closed at) holds one link and answers its close code. The restarts seen."""
        restarts, closed_at = 0, None
        while time.monotonic() < self.end_at:
            opened = time.monotonic()
            try:
                link = await WebSocketUser.open(self.port, "/ws/link", cookie)
            except (Refused, OSError) as error:
                errors.append(f"open: {error}")
                await asyncio.sleep(0.1)
                continue
            if await hold(link, opened, closed_at) != 1012:
                break
            restarts += 1  # the worker is leaving: reconnect at once, as the page's link does
            closed_at = time.monotonic()
        return restarts

    async def _read_until_closed(self, link: WebSocketUser, on_message: Callable[[int, bytes], None],
                                 tasks: list[asyncio.Future[None]]) -> int:
        """Reads link until it closes (its close code; 1006 when it just ended) or the class ends (1000); the tasks
        end with it."""
        reader = asyncio.ensure_future(link.read_messages(on_message))
        try:
            while not reader.done() and time.monotonic() < self.end_at:  # the end moves while a restart goes on
                await asyncio.wait([reader], timeout=0.25)
            return (reader.result() or 1006) if reader.done() else 1000
        except (ConnectionError, OSError):
            return 1006
        finally:
            for task in tasks:
                task.cancel()
            if not reader.done():
                link.close()
                reader.cancel()

    async def _wall(self) -> None:
        """The tutor's wall as its page holds it: the page, the wall's state and a robot's scene asked once, then the
        wall's channel on the page's link until the class ends."""
        wall = self.wall
        user = HttpUser(self.port, wall.cookie)
        try:
            for path in (f"/courses/{wall.course_id}/class/wall", f"/api/courses/{wall.course_id}/class-wall",
                         f"/api/robots/{self.students[0].robot}"):  # the first seat's, as the page asks
                status = await user.get(path)
                if status != 200:
                    wall.errors.append(f"GET {path}: {status}")
        except (ConnectionError, OSError, asyncio.IncompleteReadError) as error:
            wall.errors.append(f"GET: {error}")
        finally:
            user.close()
        try:
            wall.restarts_seen = await self._keep_link(wall.cookie, wall.errors, self._watch_wall)
        finally:
            wall.left_at = time.monotonic()

    async def _watch_wall(self, link: WebSocketUser, opened: float, closed_at: float | None) -> int:
        wall = self.wall
        link.send_text(json.dumps({"type": "subscribe", "sub": WALL_SUB,
                                   "path": f"/ws/courses/{wall.course_id}/class-wall"}))
        heard = False

        def on_message(opcode: int, payload: bytes) -> None:
            nonlocal heard
            if opcode != 1:
                return
            head, _, text = payload.decode().partition(" ")
            if head == "0":
                _note_closed(json.loads(text), wall.errors)
                return
            if head != str(WALL_SUB):
                return
            at, message = time.monotonic(), json.loads(text)
            if message.get("type") == "poses":
                wall.poses += 1
                wall.robots_shown = len(message["robots"])
                wall.shown_at = wall.shown_at or at
            elif message.get("type") == "seats":
                wall.seats += 1
            else:  # "ended" or "error": nothing the wall shows
                wall.errors.append(f"the wall said {message.get('type')}: {message.get('code', '')}")
                return
            wall.received_at.append(at)
            if not heard:
                heard = True
                if closed_at is not None:
                    wall.reconnects_s.append(at - closed_at)
                elif wall.first_open_s is None:
                    wall.first_open_s = at - opened

        return await self._read_until_closed(link, on_message, [])

    async def _console(self, student: Student, link: WebSocketUser, opened: float, closed_at: float | None) -> int:
        for sub, channel in enumerate(CHANNELS, start=1):
            link.send_text(json.dumps({"type": "subscribe", "sub": sub, "path": f"/ws/robots/{student.robot}/"
                                                                                  f"{channel}"}))
        sent: dict[int, float] = {}
        ready = asyncio.Event()
        acked = asyncio.Event()
        received_before = student.received

        def received_here() -> int:
            return student.received - received_before

        def on_message(opcode: int, payload: bytes) -> None:
            student.received += 1
            if opcode != 1:
                return
            head, _, text = payload.decode().partition(" ")
            if head == "1":
                student.telemetry += 1
                return
            if head == "0":  # the link's own news: a channel the server closed is a console that lost it
                _note_closed(json.loads(text), student.errors, CHANNELS)
                return
            if head != str(DRIVE_SUB):
                return
            message = json.loads(text)
            if message.get("type") == "ready":
                ready.set()
            elif message.get("type") == "ack":
                at = time.monotonic()
                # A command the channel superseded by a newer one (it was behind) is answered by that one's ack:
                # its time counts to this moment, so a backlog shows in the p99 rather than vanishing from it.
                for sequence in [number for number in sent if number <= message["sequence"]]:
                    student.acks_s.append(at - sent.pop(sequence))
                student.superseded += int(message.get("superseded", 0))
                if not acked.is_set():
                    acked.set()
                    if closed_at is not None:
                        student.reconnects_s.append(at - closed_at)
                    elif student.first_console_s is None:
                        student.first_console_s = at - opened
            elif message.get("type") == "error":
                student.errors.append(f"drive: {message.get('code')}")

        async def drive() -> None:
            await ready.wait()
            sequence = 0
            next_at = time.monotonic()
            while time.monotonic() < self.end_at:
                sequence += 1
                sent[sequence] = time.monotonic()
                student.drives_sent += 1
                link.send_text(f"{DRIVE_SUB} " + json.dumps({"type": "drive", "sequence": sequence,
                                                             "linear_mps": 0.1, "angular_radps": 0.3}))
                next_at += DRIVE_INTERVAL_S
                await asyncio.sleep(max(0.0, next_at - time.monotonic()))

        async def watch_seat() -> None:
            try:
                await asyncio.wait_for(acked.wait(), SEAT_WAIT_S)
            except TimeoutError:
                student.seat_lost = True  # what the console saw meanwhile says where the seat went
                opened_how = "reopened" if closed_at is not None else "opened"
                student.errors.append(f"seat lost: no drive acknowledgement {SEAT_WAIT_S:.0f} s after the console "
                                      f"{opened_how} (channel ready: {ready.is_set()}, commands unanswered: "
                                      f"{len(sent)}, messages received on this link: {received_here()})")

        return await self._read_until_closed(link, on_message, [asyncio.ensure_future(drive()),
                                                                asyncio.ensure_future(watch_seat())])

    async def _requests(self, student: Student, cookie: str) -> None:
        user = HttpUser(self.port, cookie)
        try:
            while True:
                started = time.perf_counter()
                try:
                    status = await user.get(f"/api/robots/{student.robot}")
                    if status == 200:
                        student.requests_s.append(time.perf_counter() - started)
                    else:
                        student.request_errors += 1
                except (ConnectionError, OSError, asyncio.IncompleteReadError):
                    student.request_errors += 1
                    user.close()
                await asyncio.sleep(REQUEST_INTERVAL_S)
        finally:
            user.close()


def _note_closed(control: dict[str, Any], errors: list[str], channels: tuple[str, ...] = ("the wall",)) -> None:
    """A channel the server closed (the link's own "closed" news) is a page that lost it: an error."""
    if control.get("type") == "closed":
        errors.append(f"closed {channels[control['sub'] - 1]}: {control.get('code')} {control.get('reason', '')[:60]}")
