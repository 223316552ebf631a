"""Capacity with 1 and 2 web workers: `telelab up --workers N` on PostgreSQL, loaded by logged-in users in the shape
of latency.py's capacity scenario (half watch their robot's telemetry, half poll GET /api/robots/lab-1 once a second,
each from a phase of its own), raised step by step until an ordinary request's (a poll's) p99 passes 100 ms or a
request fails. Reported per worker count: the users held at p99 <= 100 ms, and the ratio 2 workers / 1 (target
>= 1.7x). A watcher holds one /ws/link subscribed to /ws/robots/lab-1/telemetry (asked of the robot at 10 Hz; the
rate a watcher receives is reported), as a console does today.

The users rise by STEP from STEP until a step misses, then the gap between the last step held and the first missed
is halved until it is at most RESOLUTION users. Each step is measured for STEP_S seconds after the new users settled.
The same students (and their logins) serve both worker counts: one database, one secret key.

The load runs in one process of its own on asyncio (benchmarks/load_client.py: keep-alive HTTP and WebSockets framed
by hand), so its work does not share the server's interpreter. Its CPU is measured at every step and reported beside
the figures: 3 % of one core at 100 users and 7-8 % at 400 (polls and telemetry together) in the first runs here.
It also measures how late its own loop wakes (a 10 ms sleep, again and again): a reply waits that long in the load
process before it is timed, so a p99 far above that lateness is the server's.
On a 2-core machine the load generator and the two workers share the cores, so the 2-worker figure carries the
generator's share: it is reported, not subtracted, beside the share of the machine's cores busy in each window (the
lab's robot, PostgreSQL, the kernel's loopback traffic and any neighbour's work included).

    python -m benchmarks.capacity [--quick] [--output DIR]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import random
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

from benchmarks.load_client import OP_BINARY, HttpUser, LoadProcess, Refused, WebSocketUser
from benchmarks.report import Measurement, percentile_ms, print_table, write_json
from benchmarks.web_tier import (
    busy_share,
    cpu_seconds,
    create_students,
    fresh_database,
    load_average,
    log_in,
    machine_ticks,
    telelab_up,
)

ROBOT = "lab-1"
POLLED = f"/api/robots/{ROBOT}"
P99_TARGET_MS = 100.0
RATIO_TARGET = 1.7
STEP, RESOLUTION, MOST_USERS = 100, 25, 3000
STEP_S, SETTLE_S = 20.0, 3.0
QUICK_USERS, QUICK_STEP_S = (6,), 1.0  # each poller polls once in a quick window
REQUEST_TIMEOUT_S = 30.0


# --- the load process ------------------------------------------------------------------------------------------

class _Load:
    """The users of the load process: even indices watch telemetry, odd ones poll."""

    def __init__(self) -> None:
        self.port = 0
        self.tasks: list[asyncio.Future] = []
        self.latencies: list[float] = []
        self.lag_probe: asyncio.Future | None = None
        self.loop_lags: list[float] = []  # how late this process's own loop woke: a late loop delays every reply
        self.errors = self.messages = self.watching = self.lost = 0
        self._phases = random.Random(0)

    def resize(self, port: int, cookies: list[str]) -> None:
        """Users 0..len(cookies)-1 run against the server at port; the others leave (the last ones first)."""
        if port != self.port:
            self.resize(self.port, [])
            self.port = port
        while len(self.tasks) > len(cookies):
            self.tasks.pop().cancel()
        for index in range(len(self.tasks), len(cookies)):
            user = self._watch(cookies[index]) if index % 2 == 0 else self._poll(cookies[index], self._phases.random())
            self.tasks.append(asyncio.ensure_future(user))

    async def _watch(self, cookie: str) -> None:
        subscribed = False

        def on_message(opcode: int, payload: bytes) -> None:
            nonlocal subscribed
            if payload.startswith(b"1 ") or (opcode == OP_BINARY and payload[:4] == b"\0\0\0\1"):
                self.messages += 1
            elif not subscribed and payload.startswith(b"0 ") and b'"subscribed"' in payload:
                subscribed = True
                self.watching += 1

        socket = None
        try:
            socket = await WebSocketUser.open(self.port, "/ws/link", cookie)
            socket.send_text(json.dumps({"type": "subscribe", "sub": 1, "path": f"/ws/robots/{ROBOT}/telemetry"}))
            await socket.read_messages(on_message)
            self.lost += 1  # the server ended it
        except (OSError, Refused, asyncio.IncompleteReadError, asyncio.LimitOverrunError):
            self.lost += 1
        finally:
            self.watching -= subscribed
            if socket is not None:
                socket.close()

    async def _poll(self, cookie: str, phase_s: float) -> None:
        # Independent people: each polls once a second from a phase of its own (all in step would be a burst).
        user = HttpUser(self.port, cookie)
        loop = asyncio.get_running_loop()
        due = loop.time() + phase_s
        try:
            while True:
                await asyncio.sleep(max(0.0, due - loop.time()))
                due += 1.0
                started = time.perf_counter()
                try:
                    async with asyncio.timeout(REQUEST_TIMEOUT_S):
                        status = await user.get(POLLED)
                except (OSError, TimeoutError, asyncio.IncompleteReadError, asyncio.LimitOverrunError, ValueError):
                    status = 0
                    user.close()
                self.latencies.append(time.perf_counter() - started)
                self.errors += status != 200
        finally:
            user.close()


LAG_PROBE_S = 0.01


async def _probe_lag(load: _Load) -> None:
    loop = asyncio.get_running_loop()
    while True:
        asked = loop.time()
        await asyncio.sleep(LAG_PROBE_S)
        load.loop_lags.append(loop.time() - asked - LAG_PROBE_S)


async def _obey(commands, reports) -> None:
    load = _Load()
    loop = asyncio.get_running_loop()
    load.lag_probe = asyncio.ensure_future(_probe_lag(load))
    while True:
        command, argument = await loop.run_in_executor(None, commands.get)
        if command == "users":
            port, cookies = argument
            load.resize(port, cookies)
            await asyncio.sleep(0.2)  # users who leave close their connections
            wanted = (len(cookies) + 1) // 2
            deadline = loop.time() + 120
            while load.watching < wanted and loop.time() < deadline:
                await asyncio.sleep(0.1)
            reports.put(("users", {"watching": load.watching, "wanted": wanted}))
        elif command == "measure":
            load.latencies, load.loop_lags, load.errors, load.messages, load.lost = [], [], 0, 0, 0
            cpu, wall = time.process_time(), time.perf_counter()
            await asyncio.sleep(argument)
            elapsed = time.perf_counter() - wall
            reports.put(("measured", {"latencies": load.latencies, "loop_lags": load.loop_lags,
                                      "errors": load.errors, "lost": load.lost,
                                      "telemetry_hz": load.messages / elapsed / max(load.watching, 1),
                                      "cpu_share": (time.process_time() - cpu) / elapsed}))
        else:
            load.resize(load.port, [])
            await asyncio.sleep(0.5)
            reports.put(("left", None))
            if command == "stop":
                return


def run_load(commands, reports) -> None:
    """The load process: holds the users it is given (port, cookies) until told to stop."""
    asyncio.run(_obey(commands, reports))


# --- the steps ---------------------------------------------------------------------------------------------------

@dataclass
class Step:
    """One number of users on one worker count, measured."""

    workers: int
    users: int
    p50_ms: float
    p99_ms: float
    requests: int
    errors: int
    sockets_lost: int
    telemetry_hz: float
    load_cpu_share: float  # of one core
    workers_cpu_cores: float
    cores_per_worker: tuple[float, ...]  # how the kernel's accepts spread the users shows here
    machine_busy: float  # share of all the machine's cores busy (the lab, its robot, PostgreSQL, the load, neighbours)
    load_average: tuple[float, float]  # 1-minute, at the window's start and end
    load_loop_late_p99_ms: float  # the load process's own loop woke this late: replies waited as long in it

    @property
    def held(self) -> bool:
        """p99 within the target and nothing failed."""
        return self.p99_ms <= P99_TARGET_MS and self.errors == 0 and self.sockets_lost == 0


class Capacity:
    """One `telelab up --workers N` and its load process; measure(users) runs one step."""

    def __init__(self, workers: int, database_url: str, names: list[str], cookies: list[str], step_s: float) -> None:
        self.workers, self.names, self.cookies, self.step_s = workers, names, cookies, step_s
        self.load = LoadProcess(run_load)  # starts while the lab does
        try:
            self.server = telelab_up(database_url, workers)
            self.pids = self.server.wait_for_workers(workers)
        except BaseException:
            self.load.stop()
            raise
        self.steps: list[Step] = []

    def measure(self, users: int) -> Step:
        """Runs `users` users, waits for them to settle, and measures one window."""
        if len(self.cookies) < users:  # logins hash passwords: done before the window, once for both worker counts
            try:
                self.cookies += log_in(self.server.url, self.names[len(self.cookies):users])
            except RuntimeError as error:  # say why: the server's own last words
                raise RuntimeError(f"{error}; the server's last output:\n{''.join(self.server.output[-60:])}") from None
        opened = self.load.ask("users", (self.server.port, self.cookies[:users]), 300)
        time.sleep(SETTLE_S if self.step_s > QUICK_STEP_S else 0.5)
        before, machine = [cpu_seconds(pid) for pid in self.pids], machine_ticks()
        average_before, wall = load_average(), time.perf_counter()
        measured = self.load.ask("measure", self.step_s, self.step_s + 120)
        elapsed, busy = time.perf_counter() - wall, busy_share(machine, machine_ticks())
        per_worker = tuple((cpu_seconds(pid) - cpu) / elapsed for pid, cpu in zip(self.pids, before, strict=True))
        cores = sum(per_worker)
        latencies = measured["latencies"]
        step = Step(self.workers, users, percentile_ms(latencies, 50), percentile_ms(latencies, 99), len(latencies),
                    measured["errors"], measured["lost"] + max(0, opened["wanted"] - opened["watching"]),
                    measured["telemetry_hz"], measured["cpu_share"], cores, per_worker, busy,
                    (average_before, load_average()), percentile_ms(measured["loop_lags"], 99))
        self.steps.append(step)
        print(f"{self.workers} worker(s), {users} users: p50 {step.p50_ms:.1f} ms, p99 {step.p99_ms:.1f} ms, "
              f"{step.errors} errors, {step.sockets_lost} sockets lost, workers {cores:.2f} cores "
              f"({' + '.join(f'{share:.2f}' for share in per_worker)}), machine {busy * 100:.0f} % busy, load "
              f"{step.load_cpu_share * 100:.0f} % of a core, load average {step.load_average[1]:.2f}, "
              f"load loop late p99 {step.load_loop_late_p99_ms:.1f} ms", flush=True)
        return step

    def close(self) -> threading.Thread:
        """Every user leaves, then the lab stops, in a thread of its own (the next lab may start meanwhile)."""
        try:
            self.load.stop()
        finally:
            stopping = threading.Thread(target=self.server.stop)
            stopping.start()
        return stopping


def users_held(capacity: Capacity, quick: bool) -> int:
    """The most users a step held: STEP more each step until one misses, then the gap halved down to RESOLUTION."""
    if quick:
        return max([0] + [users for users in QUICK_USERS if capacity.measure(users).held])
    held, missed, users = 0, None, STEP
    while missed is None and users <= MOST_USERS:
        if capacity.measure(users).held:
            held, users = users, users + STEP
        else:
            missed = users
    while missed is not None and missed - held > RESOLUTION:
        users = (held + missed) // 2
        if capacity.measure(users).held:
            held = users
        else:
            missed = users
    return held


# --- the report --------------------------------------------------------------------------------------------------

def _rows(held: dict[int, int], steps: list[Step], quick: bool) -> list[Measurement]:
    averages = [value for step in steps for value in step.load_average]
    machine = (f"load average (1 min) {min(averages):.2f}-{max(averages):.2f} during the steps; the load generator "
               "(one process) shares the 2 cores")
    rows = []
    for workers, count in held.items():
        mine = [step for step in steps if step.workers == workers]
        at = next((step for step in mine if step.users == count), None)
        above = min((step for step in mine if step.users > count), key=lambda step: step.users, default=None)
        scenario = f"capacity, {workers} web worker{'s' if workers > 1 else ''}"
        load_note = (f"{machine}; at the users held the load generator took {at.load_cpu_share * 100:.0f} % of a "
                     f"core and the workers {at.workers_cpu_cores:.2f} cores, load average "
                     f"{at.load_average[1]:.2f}" if at else machine)
        rows += [
            Measurement(scenario, "users held at p99 <= 100 ms", float(count), "users", "-",
                        floor=float(held[1]) if workers != 1 and 1 in held else None,
                        note=load_note + ("; floor: 1 worker" if workers != 1 and 1 in held else "")),
            Measurement(scenario, "p99 at the users held", at.p99_ms if at else None, "ms", "-",
                        floor=mine[0].p99_ms, note=f"floor: the first step ({mine[0].users} users)"),
            Measurement(scenario, "p99 at the first step missed", above.p99_ms if above else None, "ms", "-",
                        note=f"{above.users} users, {above.errors} errors, {above.sockets_lost} sockets lost"
                        if above else "no step missed"),
            Measurement(scenario, "load generator CPU at the users held",
                        at.load_cpu_share * 100 if at else None, "% of a core", "-"),
            Measurement(scenario, "web workers' CPU at the users held", at.workers_cpu_cores if at else None,
                        "cores", "-", note=" + ".join(f"{share:.2f}" for share in at.cores_per_worker) if at else ""),
            Measurement(scenario, "machine busy at the users held", at.machine_busy * 100 if at else None,
                        "% of all cores", "-", note="the lab, its robot, PostgreSQL, the load generator and any "
                        "neighbour; at the first step missed: "
                        + (f"{above.machine_busy * 100:.0f} %" if above else "none")),
            Measurement(scenario, "telemetry messages/s at a watcher at the users held",
                        at.telemetry_hz if at else None, "Hz", "-", floor=mine[0].telemetry_hz,
                        note="floor: the first step"),
        ]
    if 1 in held and 2 in held:
        ratio = held[2] / held[1] if held[1] else None
        rows.append(Measurement("capacity, 2 web workers / 1", "users held, ratio", ratio, "x", f">= {RATIO_TARGET:g}",
                                passed=None if quick or ratio is None else ratio >= RATIO_TARGET, note=machine))
    return rows


def _summary(steps: list[Step]) -> str:
    """Every step in one line (a record keeps strings): workers/users -> p99, load generator CPU, load average."""
    return "; ".join(f"{step.workers}w/{step.users}u p99 {step.p99_ms:.0f} ms{'' if step.held else ' MISS'} "
                     f"(load gen {step.load_cpu_share * 100:.0f} %, workers "
                     f"{' + '.join(f'{share:.2f}' for share in step.cores_per_worker)} cores, "
                     f"machine {step.machine_busy * 100:.0f} % busy, "
                     f"load avg {step.load_average[1]:.2f}, load loop late p99 {step.load_loop_late_p99_ms:.0f} ms)"
                     for step in steps)


def search(workers: int, database_url: str, names: list[str], cookies: list[str], quick: bool) -> tuple[
        int, list[Step], threading.Thread]:
    """One worker count's users held and steps, and the thread that stops its lab."""
    capacity = Capacity(workers, database_url, names, cookies, QUICK_STEP_S if quick else STEP_S)
    try:
        held = users_held(capacity, quick)
    finally:
        stopping = capacity.close()
    return held, capacity.steps, stopping


def _quick_search(workers: int, names: list[str], students_url: str) -> tuple[int, list[Step], threading.Thread]:
    with fresh_database(copy_of=students_url) as database_url:
        held, steps, stopping = search(workers, database_url, names, [], quick=True)
        stopping.join()  # before the database goes
    return held, steps, stopping


def run(quick: bool, output: Path, worker_counts: tuple[int, ...] = (1, 2)) -> list[Measurement]:
    """Every worker count's search, one after the other on one database (its students logged in once); --quick runs
    them at once, each on a copy of one database (a smoke run measures nothing worth keeping)."""
    names = [f"capacity{i}" for i in range(max(QUICK_USERS) if quick else MOST_USERS)]
    held: dict[int, int] = {}
    steps: list[Step] = []
    if quick:
        # Migrated and given the students once (a process that imports the middleware, about 3 s of CPU): each worker
        # count's `telelab up` seeds its demo data, so the two at once run on copies, not on one database.
        with fresh_database() as students_url, ThreadPoolExecutor(len(worker_counts)) as pool:
            create_students(students_url, names, environment={"TELELAB_ROBOTS": ""})
            for workers, (count, searched, _) in zip(
                    worker_counts, pool.map(lambda workers: _quick_search(workers, names, students_url), worker_counts),
                    strict=True):
                held[workers] = count
                steps += searched
    else:
        cookies: list[str] = []
        with fresh_database() as database_url:
            create_students(database_url, names, environment={"TELELAB_ROBOTS": ""})
            stopping = []
            for workers in worker_counts:
                held[workers], searched, stopped = search(workers, database_url, names, cookies, quick=False)
                steps += searched
                stopping.append(stopped)
            for thread in stopping:
                thread.join()
    rows = _rows(held, steps, quick)
    print_table("Capacity with 1 and 2 web workers (telelab up on PostgreSQL)", rows)
    write_json(output / "capacity.json", rows, {"quick": quick, "step_s": QUICK_STEP_S if quick else STEP_S,
                                                "p99_target_ms": P99_TARGET_MS,
                                                "steps": [asdict(step) for step in steps],
                                                "steps_summary": _summary(steps)})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.capacity", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default 1 2)")
    args = parser.parse_args(argv)
    run(args.quick, args.output, tuple(args.workers))
    return 0


if __name__ == "__main__":
    sys.exit(main())
