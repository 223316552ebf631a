"""A class as it really arrives (issue 31): N students log in over a window, each opens a full console on a robot of
their own and drives it while their tutor watches the class wall, and the web workers are restarted in turn in the
middle; run with 1, 2 and 3 workers at the same load.

The web tier is gunicorn with the shared configuration (`deploy/gunicorn.conf.py`, as a web host runs it) on a fresh
PostgreSQL database, behind Debian's nginx with the site the deployment guide gives (`deploy/nginx/telelab.conf`). The
robots are stand-ins (`standin_robots.py`: the robot protocol on grpc.aio, no physics), so that the web tier is what is
measured. The class is a class session as the product opens one: the tutor (who created the course and enrolled the
students, through the courses' services) opens the course's class page and starts the session (POST
/api/courses/<id>/class-session), and the workers start every seat's robot on the lab's farm; here the farm is a process
that speaks the protocol of `telelab up`'s farm owner (`middleware/farm/owner.py`) and starts a student's practice robot
by handing the stand-in of its name the owner's token. A student's console is one `/ws/link` on their own robot carrying
telemetry (the drawn view's and the panels' feed), localization and drive, driving at the console's rate (a command
every 50 ms), and an ordinary request every second (GET /api/robots/<name>). The tutor's wall opens first and shows the
class alone for 5 s (0.5 s in `--quick`) before the first login, then stays open to the end, as its page holds it: the
page, the wall's state and one robot's scene asked once (GET), then the wall's channel (`/ws/courses/<id>/class-wall`)
on the page's `/ws/link`, which brings every seat's pose, speed, battery and activity five times a second and the seats
when they change, the page sending nothing. From the first login on, its work is in the web CPU (the student-seconds do
not count the tutor) and its messages among the messages. Halfway through the hold, SIGHUP to the gunicorn master
restarts the workers one at a time; each console, and the wall, reconnects when its link closes with 1012.

Reported per worker count, each beside a floor from the same run: web CPU per student-second (the workers and their
child processes; floor: the idle workers' CPU over the same time), its ratio to 1 worker's (target: within 10 %) and to
1 worker's carrying each worker's share of the class (a worker spends less per message the busier it is, so only this
ratio tells work done twice across workers; `--no-equal-load` leaves those runs out), the same with everyone in
before the restart (neither logins nor the restart in it; the rest of the run apart) and
per 1000 messages (a worker that falls behind supersedes drive commands, so it works less per student-second: the
commands sent on to the robot per student-second are beside it), threads per worker (floor: idle),
PostgreSQL transactions per student-second (floor: idle), the p99 of ordinary requests (floor: the same request
with nobody in) and of drive acknowledgements (floor: the robot's own Drive round trip over gRPC), the reconnect
time after the restart (floor: a console's first opening), and seats lost (target 0); the wall's messages received
per second in the class (floor: the same wall before the first login) and its reconnect time after the restart
(floor: its first opening), and the students' robots in its last poses (target: every one); beside them, the share
of drive commands the server superseded by a newer one waiting (each timed to the ack that answered it) and, among
the errors, every channel the server closed. `--quick`: 4 students over 1 s, a 4 s hold, 1 worker only.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import json
import math
import os
import platform
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.request import Request

import grpc

from benchmarks.load_client import HttpUser, Refused, WebSocketUser
from benchmarks.report import Measurement, percentile_ms, print_table, write_json
from benchmarks.standin_robots import StandInFleet
from benchmarks.web_tier import (
    ROOT,
    SECRET_KEY,
    WebServer,
    admin_dsn,
    cookie_header,
    cpu_seconds,
    create_students,
    free_port,
    fresh_database,
    log_in_one,
    logged_in,
)
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
DRIVE_INTERVAL_S = 0.05  # the console's rate (middleware/lab/sockets.py DRIVE_SEND_INTERVAL_MS)
REQUEST_INTERVAL_S = 1.0
RESTART_SETTLE_S = 3.0  # the class goes on at least this long after the last old worker left
SEAT_WAIT_S = 10.0  # a student who gets no acknowledgement this long after reconnecting has lost their seat
RATIO_TARGET = 1.10
STEADY_AFTER_LOGINS_S = 3.0  # the steady class is measured from this long after the last login to the restart
CONSOLE_WAIT_S = 60.0
# Consoles opened at once in the thread climb: gunicorn's gthread worker keeps the request threads that
# simultaneous handshakes made (up to its `threads`), which would count the load's burst, not the robots.
CONSOLES_AT_ONCE = 10
# What may grow however many robots: the pools with fixed ceilings (the sockets' blocking work, 16; the liveness
# probes, 8), and gunicorn's request threads kept from CONSOLES_AT_ONCE handshakes at once. A pump thread per
# stream was 3 a robot.
THREADS_ALLOWANCE = 16 + 8 + 10 + 4
CHANNELS = ("telemetry", "localization", "drive")
DRIVE_SUB = 3
TUTOR, COURSE_CODE = "tutor1", "CLASS-DAY"
# Each student's robot is their practice robot (middleware/teaching/practice_robots.py practice_name), and the
# stand-in of that name stands for it; one more, nobody's, is the drive floor's.
STUDENT_PREFIX = "pupil"
ROBOT_PREFIX = f"practice-{STUDENT_PREFIX}"
WALL_SUB = 1
WALL_ALONE_S = 5.0  # the wall shows the class alone this long (at most half the idle floor's) first: its floor
WALL_WAIT_S = 30.0  # the class begins without the wall's floor if it showed nothing in this time
READY_WAIT_S = 60.0  # every seat's robot started
CSRF_META = re.compile(r'<meta name="csrf-token" content="([^"]+)"')
# The local farm owner's settings (middleware/farm/owner.py ADDRESS_VARIABLE, KEY_VARIABLE), named here because this
# process does not import the middleware (seconds of a busy host); the farm's own process reads them by those names.
FARM_ADDRESS_VARIABLE, FARM_KEY_VARIABLE = "TELELAB_LOCAL_FARM", "TELELAB_LOCAL_FARM_KEY"


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
                student.seat_lost = True

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


class Nginx:
    """Debian's nginx with the deployment's site, its upstream the given web port."""

    def __init__(self, upstream_port: int, folder: Path) -> None:
        self.port = free_port()
        site = (ROOT / "deploy" / "nginx" / "telelab.conf").read_text()
        site = site.replace("server 127.0.0.1:5000;", f"server 127.0.0.1:{upstream_port};")
        site = site.replace("listen 8080;", f"listen 127.0.0.1:{self.port};")
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "telelab.conf").write_text(site)
        (folder / "nginx.conf").write_text(
            ("user root;\n" if os.geteuid() == 0 else "")
            + f"pid {folder}/nginx.pid;\nerror_log {folder}/error.log;\nworker_processes 1;\n"
            + "events { worker_connections 4096; }\n"
            + f"http {{\n  access_log off;\n  client_body_temp_path {folder}/body;\n  proxy_temp_path {folder}/proxy;\n"
            + f"  include {folder}/telelab.conf;\n}}\n")
        self.process = subprocess.Popen([NGINX, "-p", str(folder), "-c", str(folder / "nginx.conf"), "-g",
                                         "daemon off;"], stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 20
        while not _answers(self.port):
            if self.process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"nginx did not start: {self.process.stderr.read() if self.process.stderr else ''}")
            time.sleep(0.1)

    def stop(self) -> None:
        self.process.terminate()
        self.process.communicate(timeout=10)


class StandInFarm:
    """The class's farm: a process of its own that speaks the protocol of `telelab up`'s local farm owner
    (middleware/farm/owner.py), which the web workers reach as their farm, so a class session starts its students'
    robots as in the product. A start hands the stand-in of the robot's name its owner's token (SetController), as a
    farm starts a robot that obeys it; a stop takes the token back."""

    def __init__(self, fleet: StandInFleet) -> None:
        self._folder = Path(tempfile.mkdtemp(prefix="telelab-farm-"))  # mode 0700; a Unix socket's path is short
        self.environment = {FARM_ADDRESS_VARIABLE: str(self._folder / "farm.sock"),
                            FARM_KEY_VARIABLE: os.urandom(32).hex()}
        # Started now: its imports of the middleware overlap the database's set-up and the workers' start.
        self.process = subprocess.Popen([sys.executable, "-c", "import benchmarks.class_day as c; c.serve_farm()"],
                                        cwd=ROOT, env={**os.environ, **self.environment,
                                                       "TELELAB_ROBOTS": fleet.robots_setting},
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def wait_until_serving(self) -> None:
        assert self.process.stdout is not None
        if self.process.stdout.readline().strip() != "serving":
            raise RuntimeError(f"the stand-in farm did not start (exit code {self.process.wait()})")

    def stop(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()  # it serves until its stdin closes
        try:
            self.process.wait(10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)
        shutil.rmtree(self._folder, ignore_errors=True)


def serve_farm() -> None:
    """The stand-in farm's process (StandInFarm): the robots of TELELAB_ROBOTS, served until stdin closes."""
    from multiprocessing.managers import BaseManager

    from middleware.config import parse_robots
    from middleware.farm.base import Capacity, FarmRobot, RobotSpec
    from middleware.farm.owner import ADDRESS_VARIABLE, FARM_METHODS, KEY_VARIABLE

    addresses = {robot.name: robot.address for robot in parse_robots(os.environ["TELELAB_ROBOTS"])}
    started: dict[str, FarmRobot] = {}

    def hand_over(address: str, token: str) -> None:
        with grpc.insecure_channel(address) as channel:
            robot_pb2_grpc.RobotStub(channel).SetController(robot_pb2.SetControllerRequest(token=token), timeout=10)

    class Farm:
        backend = "local"

        def start(self, spec: RobotSpec) -> FarmRobot:
            hand_over(addresses[spec.name], spec.controller_token)
            started[spec.name] = FarmRobot(spec.name, spec.scene, addresses[spec.name], "localhost", self.backend)
            return started[spec.name]

        def find(self, name: str) -> FarmRobot | None:
            return started.get(name)

        def stop(self, name: str) -> bool:
            robot = started.pop(name, None)
            if robot is not None:
                hand_over(robot.address, "")
            return robot is not None

        def robots(self) -> list[FarmRobot]:
            return list(started.values())

        def capacity(self) -> Capacity:
            return Capacity(len(addresses), len(started), 1)

    class Owner(BaseManager):
        pass

    farm = Farm()
    Owner.register("farm", callable=lambda: farm, exposed=FARM_METHODS)
    server = Owner(address=os.environ[ADDRESS_VARIABLE], authkey=bytes.fromhex(os.environ[KEY_VARIABLE])).get_server()
    threading.Thread(target=lambda: (sys.stdin.read(), os._exit(0)), daemon=True).start()
    print("serving", flush=True)
    server.serve_forever()


def open_class_session(base_url: str, seats: int) -> tuple[int, str]:
    """The tutor opens their course's class page and starts the class session (its Start button's request), then
    waits until every seat's robot is ready, as the page says; the course's id and the tutor's Cookie header."""
    opener, cookies = logged_in(base_url, TUTOR)

    def answer(path: str, body: bytes | None = None, token: str = "") -> Any:
        headers = {"Accept": "application/json"}
        if body is not None:
            headers |= {"Content-Type": "application/json", "X-CSRFToken": token}
        with opener.open(Request(base_url + path, data=body, headers=headers), timeout=60) as reply:
            return json.loads(reply.read())

    (course_id,) = [course["id"] for course in answer("/api/courses")["courses"] if course["code"] == COURSE_CODE]
    with opener.open(f"{base_url}/courses/{course_id}/class", timeout=60) as page:
        found = CSRF_META.search(page.read().decode())
    if found is None:
        raise RuntimeError("the class page has no CSRF token")
    answer(f"/api/courses/{course_id}/class-session", b"{}", found.group(1))
    deadline = time.monotonic() + READY_WAIT_S
    while (counts := answer(f"/api/courses/{course_id}/class-session")["counts"])["ready"] < seats:
        if counts["failed"] or time.monotonic() > deadline:
            raise RuntimeError(f"the class session's robots did not all start: {counts}")
        time.sleep(0.2)
    return course_id, cookie_header(cookies)


def _answers(port: int) -> bool:
    import socket

    try:
        with socket.create_connection(("127.0.0.1", port), timeout=0.5):
            return True
    except OSError:
        return False


def _settled_threads(pid: int, window_s: float = 1.0) -> int:
    """The fewest threads of pid over window_s (a request thread in flight is not the worker's own)."""
    least, deadline = _threads(pid), time.monotonic() + window_s
    while time.monotonic() < deadline:
        time.sleep(0.1)
        least = min(least, _threads(pid))
    return least


def worker_pids(server: WebServer) -> list[int]:
    """The master's workers now (a worker leaving between the listing and the look is skipped)."""
    for _attempt in range(20):
        try:
            return server.worker_pids()
        except OSError:
            time.sleep(0.05)
    return []


def _descendants(pid: int) -> list[int]:
    """The processes under pid (its children, theirs, ...), from /proc/<pid>/task/<tid>/children."""
    found: list[int] = []
    with contextlib.suppress(OSError):
        for task in Path(f"/proc/{pid}/task").iterdir():
            with contextlib.suppress(OSError, ValueError):
                for child in map(int, (task / "children").read_text().split()):
                    found += [child, *_descendants(child)]
    return found


def _threads(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("Threads:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


class WorkerMeter:
    """Samples every worker of a gunicorn master (they change in a rolling restart): CPU per pid, threads."""

    def __init__(self, server: WebServer) -> None:
        self._server = server
        self._first: dict[int, float] = {}
        self._last: dict[int, float] = {}
        self.threads: list[int] = []
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._sample_forever, daemon=True)

    def start(self) -> None:
        self._sample(first=True)
        self._thread.start()

    def _sample(self, first: bool = False) -> None:
        # A worker's own child processes (a recordings writer, say) are web CPU too.
        for pid in [found for worker in worker_pids(self._server) for found in (worker, *_descendants(worker))]:
            try:
                used = cpu_seconds(pid)
            except OSError:
                continue
            with self._lock:
                self._first.setdefault(pid, used if first else 0.0)
                self._last[pid] = used

    def used_s(self) -> float:
        """The workers' CPU seconds since start, now (a phase's CPU is the difference of two readings)."""
        self._sample()
        with self._lock:
            return sum(self._last[pid] - self._first[pid] for pid in self._last)

    def _sample_forever(self) -> None:
        while not self._stop.wait(0.2):
            self._sample()

    def sample_threads(self) -> None:
        self.threads.extend(_threads(pid) for pid in worker_pids(self._server))

    def stop(self) -> float:
        """The workers' CPU seconds since start."""
        self._stop.set()
        self._thread.join(5)
        return self.used_s()


def _transactions(database_url: str) -> int:
    import psycopg

    name = database_url.rsplit("/", 1)[1]
    with psycopg.connect(admin_dsn(), autocommit=True) as admin:
        admin.execute("SELECT pg_stat_clear_snapshot()")
        row = admin.execute("SELECT xact_commit + xact_rollback FROM pg_stat_database WHERE datname = %s",
                            (name,)).fetchone()
    return int(row[0]) if row else 0


def _drive_floor(address: str, samples: int) -> list[float]:
    """The robot's own Drive round trip over gRPC (what the middleware's leg adds to)."""
    with grpc.insecure_channel(address) as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        stub.SetController(robot_pb2.SetControllerRequest(token="floor"))
        found = []
        for sequence in range(1, samples + 1):
            started = time.perf_counter()
            stub.Drive(robot_pb2.DriveCommand(token="floor", sequence=sequence, linear_mps=0.0))
            found.append(time.perf_counter() - started)
        stub.SetController(robot_pb2.SetControllerRequest(token=""))
    return found


async def _idle_requests(port: int, cookie: str, path: str, seconds: float) -> list[float]:
    user, found, end = HttpUser(port, cookie), [], time.monotonic() + seconds
    try:
        while time.monotonic() < end:
            started = time.perf_counter()
            if await user.get(path) == 200:
                found.append(time.perf_counter() - started)
            await asyncio.sleep(0.05)
    finally:
        user.close()
    return found


@dataclass
class Stretch:
    """What the web tier did in a stretch of a class: its workers' CPU, the student-seconds, PostgreSQL's
    transactions and the consoles' messages (drive commands sent, messages received, requests)."""

    cpu_s: float = 0.0
    student_s: float = 0.0
    transactions: float = 0.0
    messages: float = 0.0

    @property
    def cpu_per_student_s(self) -> float:
        return self.cpu_s / self.student_s if self.student_s else float("nan")


@dataclass
class WallFigures:
    """The tutor's wall in one class: its messages a second in the class and before it (None: none came), its first
    opening and reconnects [s], and the students' robots in its last poses."""

    per_s: float | None = None
    alone_per_s: float | None = None
    first_open_s: float | None = None
    reconnects_s: list[float] = field(default_factory=list)
    messages: int = 0
    restarts_seen: int = 0
    robots_shown: int = 0


@dataclass
class RunFigures:
    workers: int
    students: int
    student_s: float
    cpu_s: float
    idle_cpu_s: float
    threads_per_worker: int
    idle_threads_per_worker: int
    transactions: int
    idle_transactions: float
    requests_s: list[float]
    idle_requests_s: list[float]
    request_errors: int
    acks_s: list[float]
    drive_floor_s: list[float]
    reconnects_s: list[float]
    first_consoles_s: list[float]
    seats_lost: int
    never_in: int
    drives_sent: int
    superseded: int
    restarts_seen: int
    errors: list[str]
    steady: Stretch = field(default_factory=Stretch)
    idle_cpu_per_s: float = 0.0
    messages: int = 0
    wall: WallFigures = field(default_factory=WallFigures)

    @property
    def cpu_per_student_s(self) -> float:
        return self.cpu_s / self.student_s if self.student_s else float("nan")



def run_class(workers: int, students: int, login_window_s: float, hold_s: float, idle_s: float,
              folder: Path) -> RunFigures:
    """One class on `workers` workers: its session opened by the tutor, the idle floors, the tutor's wall alone, then
    the class with a rolling restart halfway through the hold."""
    names = [f"{STUDENT_PREFIX}{i + 1}" for i in range(students)]
    fleet = StandInFleet(students + 1, ROBOT_PREFIX)
    robots = list(fleet.addresses)
    farm = StandInFarm(fleet)
    try:
        with fresh_database() as database_url:
            phase = time.monotonic()
            create_students(database_url, names, course_code=COURSE_CODE, tutor=TUTOR)
            print(f"  database and {students} students in a course ready in {time.monotonic() - phase:.1f} s",
                  flush=True)
            phase = time.monotonic()
            web_port = free_port()
            server = WebServer([sys.executable, "-m", "gunicorn", "-c", "deploy/gunicorn.conf.py", "-w", str(workers),
                                "-b", "127.0.0.1:{port}", "middleware:create_app()"],
                               {"TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": SECRET_KEY,
                                "TELELAB_ROBOTS": "", **farm.environment}, port=web_port)
            nginx = None
            try:
                server.wait_for_workers(workers)
                nginx = Nginx(web_port, folder / f"nginx-{workers}")
                farm.wait_until_serving()  # the workers reach it once the class session starts
                print(f"  {workers} worker(s), nginx and the farm serving in {time.monotonic() - phase:.1f} s",
                      flush=True)
                return _measure(server, nginx.port, fleet, robots, names, database_url, workers, login_window_s,
                                hold_s, idle_s)
            finally:
                if nginx is not None:
                    nginx.stop()
                server.stop(signal.SIGTERM)
    finally:
        farm.stop()
        fleet.stop()


def _measure(server: WebServer, port: int, fleet: StandInFleet, robots: list[str], names: list[str],
             database_url: str, workers: int, login_window_s: float, hold_s: float, idle_s: float) -> RunFigures:
    phase = time.monotonic()
    course_id, tutor_cookie = open_class_session(f"http://127.0.0.1:{port}", len(names))
    print(f"  the class session open, every seat's robot ready, in {time.monotonic() - phase:.1f} s", flush=True)
    probe_cookie = log_in_one(f"http://127.0.0.1:{port}", names[0])
    drive_floor = _drive_floor(fleet.addresses[robots[-1]], 200)
    # The idle floors: nobody in but one probe asking the ordinary request (of their own robot, as a student does).
    meter = WorkerMeter(server)
    meter.start()
    transactions_before = _transactions(database_url)
    idle_requests = asyncio.run(_idle_requests(port, probe_cookie, f"/api/robots/{robots[0]}", idle_s))
    meter.sample_threads()
    idle_threads = max(meter.threads)
    idle_cpu_per_s = meter.stop() / idle_s
    idle_transactions_per_s = (_transactions(database_url) - transactions_before) / idle_s
    # The class.
    students = [Student(name, robots[i], login_window_s * i / max(1, len(names) - 1) if len(names) > 1 else 0.0)
                for i, name in enumerate(names)]
    wall = Wall(course_id, tutor_cookie)
    meter = WorkerMeter(server)
    class_began: list[float] = []  # the transactions when the class began
    load = ClassLoad(port, students, wall, login_window_s + hold_s)
    readings: list[tuple[float, Stretch]] = []  # (when, the totals so far) at the steady stretch's start and end

    def read_totals() -> None:
        readings.append((time.monotonic(), Stretch(meter.used_s(), 0.0, _transactions(database_url),
                                                   sum(s.messages for s in students) + len(wall.received_at))))

    def restart_in_the_middle() -> None:
        try:
            load.began.wait()  # the class is measured from its start, the wall's floor before it
            started = load.started
            time.sleep(max(0.0, started - time.monotonic()))
            meter.start()
            class_began.append(_transactions(database_url))
            # The steady class: everyone in (the last login a moment ago) until the restart; its CPU and transactions
            # apart, as neither the logins nor the restart weigh on them.
            steady_from = started + login_window_s + min(STEADY_AFTER_LOGINS_S, hold_s / 4)
            restart_at = started + login_window_s + hold_s / 2
            time.sleep(max(0.0, steady_from - time.monotonic()))
            read_totals()
            time.sleep(max(0.0, restart_at - 1.0 - time.monotonic()))
            meter.sample_threads()  # everyone is in, before the restart
            time.sleep(max(0.0, restart_at - time.monotonic()))
            read_totals()
            print(f"rolling restart of the {workers} worker(s)", flush=True)
            leaving = set(worker_pids(server))
            server.process.send_signal(signal.SIGHUP)
            deadline = time.monotonic() + 120
            while leaving & set(worker_pids(server)) and time.monotonic() < deadline:
                time.sleep(0.2)
            load.end_at = max(load._end_at, time.monotonic() + RESTART_SETTLE_S)  # every console back, driving
        finally:
            load.restart_done = True

    restarter = threading.Thread(target=restart_in_the_middle, daemon=True)
    restarter.start()
    asyncio.run(load.run(min(WALL_ALONE_S, idle_s / 2)))
    started = load.started
    elapsed_s = time.monotonic() - started
    cpu_s = meter.stop()
    restarter.join(120)
    time.sleep(1.0)  # pg_stat_database's counters lag up to a second behind the transactions
    transactions = _transactions(database_url) - class_began[0]
    student_s = sum((s.out_at or 0) - (s.in_at or 0) for s in students if s.in_at is not None)
    errors = [f"{TUTOR}'s wall: {e}" for e in wall.errors] + [f"{s.name}: {e}" for s in students for e in s.errors]
    wall_figures = WallFigures(  # its floor from its first poses (the seats come just before, once)
        per_s=wall.per_s(started, wall.left_at or started), first_open_s=wall.first_open_s,
        alone_per_s=wall.per_s(wall.shown_at, started) if wall.shown_at is not None else None,
        reconnects_s=wall.reconnects_s, messages=len(wall.received_at), restarts_seen=wall.restarts_seen,
        robots_shown=wall.robots_shown)
    steady = Stretch()
    if len(readings) == 2:
        (start, first), (end, last) = readings
        steady = Stretch(last.cpu_s - first.cpu_s, _student_s_between(students, start, end),
                         last.transactions - first.transactions, last.messages - first.messages)
    return RunFigures(
        steady=steady, idle_cpu_per_s=idle_cpu_per_s, wall=wall_figures,
        messages=sum(s.messages for s in students) + sum(at > started for at in wall.received_at),
        workers=workers, students=len(students), student_s=student_s, cpu_s=cpu_s,
        idle_cpu_s=idle_cpu_per_s * elapsed_s, threads_per_worker=max(meter.threads or [0]),
        idle_threads_per_worker=idle_threads, transactions=transactions,
        idle_transactions=idle_transactions_per_s * elapsed_s,
        requests_s=[r for s in students for r in s.requests_s], idle_requests_s=idle_requests,
        request_errors=sum(s.request_errors for s in students), acks_s=[a for s in students for a in s.acks_s],
        drive_floor_s=drive_floor, reconnects_s=[r for s in students for r in s.reconnects_s],
        first_consoles_s=[s.first_console_s for s in students if s.first_console_s is not None],
        seats_lost=sum(s.seat_lost for s in students), never_in=sum(s.in_at is None for s in students),
        drives_sent=sum(s.drives_sent for s in students), superseded=sum(s.superseded for s in students),
        restarts_seen=sum(s.restarts_seen for s in students), errors=errors[:30])


def _student_s_between(students: list[Student], start: float, end: float) -> float:
    """The student-seconds of the class between two moments (each student from their login to their leaving)."""
    return sum(max(0.0, min(end, s.out_at or end) - max(start, s.in_at)) for s in students if s.in_at is not None)


async def _open_consoles(port: int, cookies: list[str], robots: list[str]) -> tuple[list[WebSocketUser], int]:
    """A console (camera, telemetry, localization and drive on one link) per robot, each once its channels sent
    their first message (at most CONSOLE_WAIT_S); robots are shared out over the students (a user holds at most 40
    sockets). The links, and how many consoles did not open whole."""
    async def one(index: int, robot: str) -> tuple[WebSocketUser | None, bool]:
        try:
            link = await WebSocketUser.open(port, "/ws/link", cookies[index % len(cookies)])
        except (Refused, OSError):
            return None, False
        channels = ("camera", *CHANNELS)
        for sub, channel in enumerate(channels, start=1):
            link.send_text(json.dumps({"type": "subscribe", "sub": sub, "path": f"/ws/robots/{robot}/{channel}"}))
        waiting = set(range(1, len(channels) + 1))
        done = asyncio.Event()

        def on_message(opcode: int, payload: bytes) -> None:
            sub = int.from_bytes(payload[:4], "big") if opcode == 2 else int(payload.split(b" ", 1)[0])
            waiting.discard(sub)
            if not waiting:
                done.set()

        link.reader = asyncio.ensure_future(link.read_messages(on_message))  # type: ignore[attr-defined]
        try:
            await asyncio.wait_for(done.wait(), CONSOLE_WAIT_S)
        except TimeoutError:
            return link, False
        return link, True

    opened: list[tuple[WebSocketUser | None, bool]] = []
    for start in range(0, len(robots), CONSOLES_AT_ONCE):  # as a class arrives, not all in one instant
        opened += await asyncio.gather(*(one(start + i, robot)
                                         for i, robot in enumerate(robots[start:start + CONSOLES_AT_ONCE])))
    return [link for link, _whole in opened if link is not None], sum(not whole for _link, whole in opened)


def threads_with_robots(steps: tuple[int, ...], students: int) -> list[tuple[int, int, int]]:
    """(robots with a console open, the worker's threads) at each step, on one worker (gunicorn, the shared
    configuration) with stand-in robots: a worker's threads do not grow with its robots (no pump thread per stream)."""
    names = [f"pupil{i + 1}" for i in range(students)]
    fleet = StandInFleet(max(steps), "wall-robot-")
    robots = list(fleet.addresses)
    found: list[tuple[int, int, int]] = []  # (robots, threads, consoles that did not open whole)
    try:
        with fresh_database() as database_url:
            create_students(database_url, names)
            server = WebServer([sys.executable, "-m", "gunicorn", "-c", "deploy/gunicorn.conf.py", "-w", "1", "-b",
                                "127.0.0.1:{port}", "middleware:create_app()"],
                               {"TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": SECRET_KEY,
                                "TELELAB_ROBOTS": fleet.robots_setting})
            try:
                (worker,) = server.wait_for_workers(1)
                cookies = [log_in_one(server.url, name) for name in names]

                async def climb() -> None:
                    opened: list[WebSocketUser] = []
                    asked = 0
                    for step in steps:
                        links, not_whole = await _open_consoles(server.port, cookies, robots[asked:step])
                        opened += links
                        asked = step
                        await asyncio.sleep(2.0)  # the handshakes' request threads return to the server
                        found.append((step, _settled_threads(worker), not_whole))
                        missing = f" ({not_whole} consoles not whole in {CONSOLE_WAIT_S:g} s)" if not_whole else ""
                        print(f"  {step} robots with a console open: {found[-1][1]} threads in the worker{missing}",
                              flush=True)
                    for link in opened:
                        link.close()

                asyncio.run(climb())
            finally:
                server.stop(signal.SIGTERM)
    finally:
        fleet.stop()
    return found


def machine() -> dict[str, object]:
    """What the machine was."""
    model = ""
    with contextlib.suppress(OSError):
        model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                      if line.startswith("model name")), "")
    memory_gb = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    return {"cores": os.cpu_count(), "cpu": model, "memory_gb": round(memory_gb, 1), "system": platform.platform(),
            "python": platform.python_version(), "load_average_at_start": os.getloadavg()[0]}


def rows_for(figures: RunFigures, one_worker_cpu: float | None, graded: bool,
             one_worker_steady_cpu: float | None = None, same_load: RunFigures | None = None) -> list[Measurement]:
    scenario = f"{figures.students} students, {figures.workers} worker(s)"
    reconnect_p50 = statistics.median(figures.reconnects_s) if figures.reconnects_s else float("nan")
    ratio = figures.cpu_per_student_s / one_worker_cpu if one_worker_cpu else None
    steady = figures.steady
    steady_ratio = (steady.cpu_per_student_s / one_worker_steady_cpu
                    if one_worker_steady_cpu and not math.isnan(steady.cpu_per_student_s) else None)
    request_p99, ack_p99 = percentile_ms(figures.requests_s, 99), percentile_ms(figures.acks_s, 99)
    rows = [
        Measurement(scenario, "web CPU per student-second (floor: idle workers)", figures.cpu_per_student_s * 1000,
                    "ms", "-", floor=figures.idle_cpu_s / figures.student_s * 1000 if figures.student_s else None),
        Measurement(scenario, "web CPU per student-second, everyone in before the restart (floor: idle workers)",
                    steady.cpu_per_student_s * 1000, "ms", "-", floor=figures.idle_cpu_per_s / figures.students * 1000),
        Measurement(scenario, "web CPU per 1000 messages, everyone in before the restart (drive commands, messages "
                              "received, requests)", steady.cpu_s / steady.messages * 1e6 if steady.messages else None,
                    "ms", "-"),
        Measurement(scenario, "PostgreSQL transactions per student-second, everyone in before the restart",
                    steady.transactions / steady.student_s if steady.student_s else None, "count", "-"),
        Measurement(scenario, "web CPU per student-second of the rest: the logins, the restart and after",
                    (figures.cpu_s - steady.cpu_s) / (figures.student_s - steady.student_s) * 1000
                    if figures.student_s > steady.student_s else None, "ms", "-"),
        Measurement(scenario, "threads per worker, everyone in (floor: idle)", float(figures.threads_per_worker),
                    "count", "-", floor=float(figures.idle_threads_per_worker)),
        Measurement(scenario, "PostgreSQL transactions per student-second (floor: idle)",
                    figures.transactions / figures.student_s if figures.student_s else None, "count", "-",
                    floor=figures.idle_transactions / figures.student_s if figures.student_s else None),
        Measurement(scenario, "ordinary request p99 (floor: nobody in)", request_p99, "ms", "-",
                    floor=percentile_ms(figures.idle_requests_s, 99)),
        Measurement(scenario, "drive acknowledgement p99 (floor: the robot's own gRPC Drive)", ack_p99, "ms", "-",
                    floor=percentile_ms(figures.drive_floor_s, 99)),
        Measurement(scenario, "reconnect after the restart, p50 (floor: a console's first opening)",
                    reconnect_p50 * 1000, "ms", "-",
                    floor=statistics.median(figures.first_consoles_s) * 1000 if figures.first_consoles_s else None),
        Measurement(scenario, "reconnect after the restart, max", max(figures.reconnects_s, default=float("nan"))
                    * 1000, "ms", "-"),
        *_wall_rows(scenario, figures.wall, figures.students, graded),
        Measurement(scenario, "drive commands sent on to the robot per student-second (the rest superseded)",
                    (figures.drives_sent - figures.superseded) / figures.student_s if figures.student_s else None,
                    "count", "-"),
        Measurement(scenario, "drive commands superseded by a newer one waiting (share of those sent)",
                    figures.superseded / figures.drives_sent * 100 if figures.drives_sent else None, "%", "-"),
        Measurement(scenario, "seats lost", float(figures.seats_lost + figures.never_in), "count", "= 0",
                    passed=figures.seats_lost + figures.never_in == 0 if graded else None),
        Measurement(scenario, "ordinary request errors", float(figures.request_errors), "count", "-"),
    ]
    if steady_ratio is not None and figures.workers > 1:
        rows.insert(3, Measurement(scenario, "web CPU per student-second before the restart / 1 worker's",
                                   steady_ratio, "ratio", "-", floor=1.0))
    if same_load is not None and figures.workers > 1:
        rows[2:2] = _same_load_rows(scenario, figures, same_load)
    if ratio is not None and figures.workers > 1:
        rows.insert(1, Measurement(scenario, "web CPU per student-second / 1 worker's", ratio, "ratio",
                                   f"<= {RATIO_TARGET:g}", floor=1.0,
                                   passed=ratio <= RATIO_TARGET if graded else None))
    return rows


def _wall_rows(scenario: str, wall: WallFigures, students: int, graded: bool) -> list[Measurement]:
    """The tutor's wall: what it received, how soon it came back after the restart, and whether it showed the class."""
    def ms(seconds: float | None) -> float | None:
        return None if seconds is None else seconds * 1000

    return [
        Measurement(scenario, "tutor's wall: messages received per second (floor: the wall before the first login)",
                    wall.per_s, "count", "-", floor=wall.alone_per_s),
        Measurement(scenario, "tutor's wall: reconnect after the restart, max (floor: its first opening)",
                    ms(max(wall.reconnects_s, default=None)), "ms", "-", floor=ms(wall.first_open_s)),
        Measurement(scenario, "tutor's wall: students' robots in its last poses", float(wall.robots_shown), "count",
                    f"= {students}", passed=wall.robots_shown == students if graded else None),
    ]


def _same_load_rows(scenario: str, figures: RunFigures, alone: RunFigures) -> list[Measurement]:
    """The workers' CPU per student-second over one worker's carrying as many students as each of them: a worker
    spends less per message the busier it is (one wake-up serves more), so this ratio, not the one at the same class
    size, tells work done twice across workers from a worker's efficiency at its load."""
    rows = [Measurement(scenario, f"web CPU per student-second / 1 worker's carrying {alone.students} students "
                                  "(the load of each)", figures.cpu_per_student_s / alone.cpu_per_student_s
                        if alone.cpu_per_student_s else None, "ratio", "-", floor=1.0)]
    if not math.isnan(figures.steady.cpu_per_student_s) and not math.isnan(alone.steady.cpu_per_student_s):
        rows.append(Measurement(scenario, f"web CPU per student-second before the restart / 1 worker's carrying "
                                          f"{alone.students} students", figures.steady.cpu_per_student_s
                                / alone.steady.cpu_per_student_s, "ratio", "-", floor=1.0))
    return rows


def _write(output: Path, rows: list[Measurement], extra: dict[str, object]) -> None:
    for row in rows:  # a figure with no sample (no reconnect in a run) is absent, not NaN
        if row.measured is not None and math.isnan(row.measured):
            row.measured = None
        if row.floor is not None and math.isnan(row.floor):
            row.floor = None
    write_json(output / "class_day.json", rows, extra)


def run(quick: bool, output: Path, students: int | None = None, workers: tuple[int, ...] | None = None,
        login_window_s: float | None = None, hold_s: float | None = None, thread_climb: bool = True,
        equal_load: bool = True) -> list:
    students = students or (4 if quick else 50)
    workers = workers or ((1,) if quick else (1, 2, 3))
    default_login_s, default_hold_s, idle_s = (1.0, 4.0, 1.0) if quick else (60.0, 40.0, 10.0)
    login_window_s = default_login_s if login_window_s is None else login_window_s
    hold_s = default_hold_s if hold_s is None else hold_s
    output.mkdir(parents=True, exist_ok=True)
    the_machine = machine()
    rows: list[Measurement] = []
    runs = []
    one_worker_cpu: float | None = None
    one_worker_steady_cpu: float | None = None
    for count in workers:
        print(f"a class of {students} on {count} worker(s): logins over {login_window_s:g} s, {hold_s:g} s held, "
              "a rolling restart halfway", flush=True)
        figures = run_class(count, students, login_window_s, hold_s, idle_s, output / "class-day")
        if count == 1:
            one_worker_cpu, one_worker_steady_cpu = figures.cpu_per_student_s, figures.steady.cpu_per_student_s
        same_load = None
        if count > 1 and equal_load:
            each = round(students / count)
            print(f"a class of {each} (each worker's share) on 1 worker, for the ratio at the same load per worker",
                  flush=True)
            same_load = run_class(1, each, login_window_s, hold_s, idle_s, output / "class-day")
        rows += rows_for(figures, one_worker_cpu, not quick, one_worker_steady_cpu, same_load)
        runs.append({"workers": count, "student_s": figures.student_s, "cpu_s": figures.cpu_s,
                     "steady": dataclasses.asdict(figures.steady), "messages": figures.messages,
                     "restarts_seen": figures.restarts_seen, "reconnects": len(figures.reconnects_s),
                     "acks": len(figures.acks_s), "drives_sent": figures.drives_sent,
                     "superseded": figures.superseded, "requests": len(figures.requests_s),
                     "wall": dataclasses.asdict(figures.wall), "errors": figures.errors})
    extra: dict[str, object] = {"students": students, "workers": list(workers), "login_window_s": login_window_s,
                                "hold_s": hold_s, "machine": the_machine, "runs": runs,
                                "recordings": os.environ.get("TELELAB_RECORDINGS", "1")}
    _write(output, rows, extra)  # the class's figures are kept whatever the climb below does
    if not thread_climb:
        print_table(f"A class of {students} on its own robots, behind nginx, with a rolling restart", rows)
        return rows
    steps = (1, 4) if quick else (1, 50, 200)
    print(f"threads of one worker with consoles open on {', '.join(map(str, steps))} robots", flush=True)
    climb = threads_with_robots(steps, max(1, min(students, max(steps) // 4 + 1)))
    scenario = "one worker, a console per robot"
    for step, threads, _not_whole in climb:
        rows.append(Measurement(scenario, f"worker threads with {step} robots' consoles (floor: 1 robot's)",
                                float(threads), "count", f"<= {climb[0][1] + THREADS_ALLOWANCE}",
                                floor=float(climb[0][1]),
                                passed=threads <= climb[0][1] + THREADS_ALLOWANCE if not quick else None))
    print_table(f"A class of {students} on its own robots, behind nginx, with a rolling restart", rows)
    extra["threads_with_robots"] = [{"robots": step, "threads": threads, "consoles_not_whole": not_whole}
                                    for step, threads, not_whole in climb]
    _write(output, rows, extra)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    parser.add_argument("--students", type=int, default=None, help="the class's size (50 here, 200 on bigger hosts)")
    parser.add_argument("--workers", type=int, nargs="+", default=None)
    parser.add_argument("--login-window", type=float, default=None, help="seconds the logins spread over (60)")
    parser.add_argument("--hold", type=float, default=None, help="seconds the class is held after (40)")
    parser.add_argument("--no-thread-climb", action="store_true",
                        help="leave out the threads-with-robots climb (a comparison of the class alone)")
    parser.add_argument("--no-equal-load", action="store_true",
                        help="leave out the 1-worker classes of each worker's share (the ratio at the same load)")
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output), args.students, tuple(args.workers) if args.workers else None,
        args.login_window, args.hold, not args.no_thread_climb, not args.no_equal_load)
    return 0


if __name__ == "__main__":
    sys.exit(main())
