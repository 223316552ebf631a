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
import dataclasses
import json
import os
import re
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any
from urllib.request import Request

import grpc

from benchmarks.class_farm import StandInFarm
from benchmarks.class_figures import RunFigures, Stretch, WallFigures, machine, rows_for, write_figures
from benchmarks.class_host import Nginx, WorkerMeter, database_transactions, settled_threads, worker_pids
from benchmarks.class_load import CHANNELS, ClassLoad, Student, Wall
from benchmarks.load_client import HttpUser, Refused, WebSocketUser
from benchmarks.report import Measurement, print_table
from benchmarks.standin_robots import StandInFleet
from benchmarks.web_tier import (
    SECRET_KEY,
    WebServer,
    cookie_header,
    create_students,
    free_port,
    fresh_database,
    log_in_one,
    logged_in,
)
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

RESTART_SETTLE_S = 3.0  # the class goes on at least this long after the last old worker left
STEADY_AFTER_LOGINS_S = 3.0  # the steady class is measured from this long after the last login to the restart
CONSOLE_WAIT_S = 60.0
# Consoles opened at once in the thread climb: gunicorn's gthread worker keeps the request threads that
# simultaneous handshakes made (up to its `threads`), which would count the load's burst, not the robots.
CONSOLES_AT_ONCE = 10
# What may grow however many robots: the pools with fixed ceilings (the sockets' blocking work, 16; the liveness
# probes, 8), and gunicorn's request threads kept from CONSOLES_AT_ONCE handshakes at once. A pump thread per
# stream was 3 a robot.
THREADS_ALLOWANCE = 16 + 8 + 10 + 4
TUTOR, COURSE_CODE = "tutor1", "CLASS-DAY"
# Each student's robot is their practice robot (middleware/teaching/practice_robots.py practice_name), and the
# stand-in of that name stands for it; one more, nobody's, is the drive floor's.
STUDENT_PREFIX = "pupil"
ROBOT_PREFIX = f"practice-{STUDENT_PREFIX}"
WALL_ALONE_S = 5.0  # the wall shows the class alone this long (at most half the idle floor's) first: its floor
READY_WAIT_S = 60.0  # every seat's robot started
CSRF_META = re.compile(r'<meta name="csrf-token" content="([^"]+)"')


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
    transactions_before = database_transactions(database_url)
    idle_requests = asyncio.run(_idle_requests(port, probe_cookie, f"/api/robots/{robots[0]}", idle_s))
    meter.sample_threads()
    idle_threads = max(meter.threads)
    idle_cpu_per_s = meter.stop() / idle_s
    idle_transactions_per_s = (database_transactions(database_url) - transactions_before) / idle_s
    # The class.
    students = [Student(name, robots[i], login_window_s * i / max(1, len(names) - 1) if len(names) > 1 else 0.0)
                for i, name in enumerate(names)]
    wall = Wall(course_id, tutor_cookie)
    meter = WorkerMeter(server)
    class_began: list[float] = []  # the transactions when the class began
    load = ClassLoad(port, students, wall, login_window_s + hold_s)
    readings: list[tuple[float, Stretch]] = []  # (when, the totals so far) at the steady stretch's start and end

    def read_totals() -> None:
        readings.append((time.monotonic(), Stretch(meter.used_s(), 0.0, database_transactions(database_url),
                                                   sum(s.messages for s in students) + len(wall.received_at))))

    def restart_in_the_middle() -> None:
        try:
            load.began.wait()  # the class is measured from its start, the wall's floor before it
            started = load.started
            time.sleep(max(0.0, started - time.monotonic()))
            meter.start()
            class_began.append(database_transactions(database_url))
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
    transactions = database_transactions(database_url) - class_began[0]
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
                        found.append((step, settled_threads(worker), not_whole))
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
    write_figures(output, rows, extra)  # the class's figures are kept whatever the climb below does
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
    write_figures(output, rows, extra)
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
