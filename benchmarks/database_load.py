"""Database load at idle logged-in users: 200 students each keep a console open and do nothing for 30 s, and what
reaches PostgreSQL is counted from pg_stat_database for the benchmark's own database (transactions committed and
rolled back, rows returned and written), read through another database so that reading adds nothing.

Three servers, one after the other, each on a fresh database, with the same two skill servers (lab-1 and lab-2,
the students split between them):

- **before** (the floor): the code of commit 163cb08, the last before the event bus (e47c78e: "chat, the robots table
  and queue pages wake on them instead of polling"), taken with `git archive` and served as its `telelab up` served
  then (`telelab web`: Werkzeug, a thread per socket). A console then opened one socket per channel, so each student
  holds /ws/robots/<r>/queue and /ws/robots/<r>/chat. Then every queue socket re-read the queue and its controller's
  name every 0.5 s, wrote its heartbeat every 2 s and re-checked its login every 5 s, and the chat hub read each
  room with sockets every 0.5 s.
- **after**: today's code under gunicorn (-k gthread --threads 200 -w 1), woken by LISTEN/NOTIFY; each student holds
  one /ws/link subscribed to their robot's queue and chat, as in benchmarks/consoles.py.
- **unable to hear**: today's code with its event bus's listener kept from connecting (`app_that_cannot_hear`), so
  it reads the tables where it would have been told, as a worker does while its listener reconnects.

A transaction is one or more statements (a read opens one, its session's end rolls it back): transactions are a
floor of the statements. pg_stat_statements, which would count statements, needs shared_preload_libraries and a
server restart. A backend reports its counters at most once a second, so a window's edges are blurred by about a
second of activity. Before the consoles open, the same counters are read for a while with nobody connected (the
server's own background work). The consoles are held by one load process (asyncio, benchmarks/load_client.py).

    python -m benchmarks.database_load [--quick] [--output DIR] [--users N]
"""

from __future__ import annotations

import argparse
import asyncio
import io
import json
import subprocess
import sys
import tarfile
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

from benchmarks.load_client import LoadProcess, Refused, WebSocketUser
from benchmarks.report import Measurement, print_table, write_json
from benchmarks.web_tier import (
    ROOT,
    SECRET_KEY,
    WebServer,
    admin_dsn,
    cpu_seconds,
    create_students,
    fresh_database,
    load_average,
    log_in,
)

BEFORE_COMMIT = "163cb08"  # the parent of e47c78e, which brought the event bus
ROBOTS = ("lab-1", "lab-2")
USERS_FULL, USERS_QUICK = 200, 6
WINDOW_S, WINDOW_QUICK_S = 30.0, 2.0
EMPTY_S = 10.0  # not in quick mode: a backend reports its counters only about once a second
SETTLE_S, SETTLE_QUICK_S = 5.0, 0.3
GUNICORN = [sys.executable, "-m", "gunicorn", "-k", "gthread", "--threads", "200", "-w", "1", "-b", "127.0.0.1:{port}",
            "--log-level", "warning"]


def app_that_cannot_hear():
    """Today's app whose event bus never connects its PostgreSQL listener (gunicorn: `app_that_cannot_hear()`).

    Everything that would be told of a change falls back to what it does while the listener reconnects."""
    from middleware import create_app, events

    events.EventBus._listen_forever = lambda self: self._stop.wait()  # type: ignore[method-assign]
    return create_app()


@dataclass(frozen=True)
class Code:
    """A version of the server: where its code is, how it is served, and how a console opens its channels."""

    key: str
    scenario: str
    command: list[str]
    one_link: bool  # one /ws/link carrying both channels, or a socket per channel


def versions(before_tree: Path | None) -> list[tuple[Code, Path]]:
    """The servers measured, with the checkout each runs from."""
    found = [(Code("after", "today (woken by events)", [*GUNICORN, "middleware:create_app()"], True), ROOT),
             (Code("deaf", "today, listener unable to hear (reads the tables)",
                   [*GUNICORN, "benchmarks.database_load:app_that_cannot_hear()"], True), ROOT)]
    if before_tree is not None:
        command = [sys.executable, "-c", "import sys; from middleware.cli import main; "
                   "sys.exit(main(['web', '--host', '127.0.0.1', '--port', '{port}']))"]
        found.insert(0, (Code("before", f"before events ({BEFORE_COMMIT}: polling)", command, False), before_tree))
    return found


def extract_before(into: Path) -> Path | None:
    """The checkout of BEFORE_COMMIT (from this repository's history), or None where there is no history."""
    archive = subprocess.run(["git", "archive", "--format=tar", BEFORE_COMMIT], cwd=ROOT, capture_output=True,
                             check=False)
    if archive.returncode != 0:
        print(f"no checkout of {BEFORE_COMMIT} ({archive.stderr.decode().strip()}): 'before' is not measured")
        return None
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        tar.extractall(into, filter="data")
    return into


# --- the load process: idle consoles ---------------------------------------------------------------------------

class _Consoles:
    def __init__(self) -> None:
        self.tasks: list[asyncio.Future] = []
        self.open = self.messages = self.ended = 0
        self.codes: list[int | None] = []

    async def _socket(self, port: int, cookie: str, path: str, subscribe: list[str]) -> None:
        opened = 0

        def on_message(_opcode: int, payload: bytes) -> None:
            nonlocal opened
            if subscribe and payload.startswith(b"0 "):
                if b'"subscribed"' in payload:
                    opened += 1
                    self.open += 1
                return
            if not subscribe and not opened:  # a channel of its own says something at once (seat, history)
                opened = 1
                self.open += 1
            self.messages += 1

        socket = None
        try:
            socket = await WebSocketUser.open(port, path, cookie)
            for sub, channel in enumerate(subscribe, start=1):
                socket.send_text(json.dumps({"type": "subscribe", "sub": sub, "path": channel}))
            self.codes.append(await socket.read_messages(on_message))
            self.ended += 1
        except (OSError, Refused, asyncio.IncompleteReadError, asyncio.LimitOverrunError):
            self.ended += 1
        finally:
            self.open -= opened
            if socket is not None:
                socket.close()

    def start(self, port: int, cookies: list[str], one_link: bool) -> None:
        for index, cookie in enumerate(cookies):
            channels = [f"/ws/robots/{ROBOTS[index % len(ROBOTS)]}/{name}" for name in ("queue", "chat")]
            if one_link:
                self.tasks.append(asyncio.ensure_future(self._socket(port, cookie, "/ws/link", channels)))
            else:
                self.tasks += [asyncio.ensure_future(self._socket(port, cookie, path, [])) for path in channels]

    def leave(self) -> None:
        for task in self.tasks:
            task.cancel()
        self.tasks = []


async def _obey(commands, reports) -> None:
    consoles = _Consoles()
    loop = asyncio.get_running_loop()
    while True:
        command, argument = await loop.run_in_executor(None, commands.get)
        if command == "open":
            port, cookies, one_link = argument
            started = time.perf_counter()
            consoles.start(port, cookies, one_link)
            while consoles.open < 2 * len(cookies) and time.perf_counter() - started < 120:
                await asyncio.sleep(0.05)
            reports.put(("open", {"channels": consoles.open, "seconds": time.perf_counter() - started}))
        elif command == "idle":
            consoles.messages, consoles.ended = 0, 0
            cpu, wall = time.process_time(), time.perf_counter()
            await asyncio.sleep(argument)
            elapsed = time.perf_counter() - wall
            reports.put(("idle", {"channels": consoles.open, "ended": consoles.ended,
                                  "messages_per_s": consoles.messages / elapsed,
                                  "cpu_share": (time.process_time() - cpu) / elapsed}))
        else:
            consoles.leave()
            await asyncio.sleep(0.3)
            reports.put((command, None))
            if command == "stop":
                return


def run_consoles(commands, reports) -> None:
    """The load process: opens idle consoles when told, and keeps them open."""
    asyncio.run(_obey(commands, reports))


# --- the counters ----------------------------------------------------------------------------------------------

COUNTERS = ("xact_commit + xact_rollback", "tup_returned", "tup_fetched", "tup_inserted + tup_updated + tup_deleted")


class DatabaseCounters:
    """pg_stat_database's counters of one database, read through the administrative database."""

    def __init__(self, database_url: str) -> None:
        import psycopg

        self.name = database_url.rsplit("/", 1)[1]
        self._admin = psycopg.connect(admin_dsn(), autocommit=True)

    def read(self) -> tuple[float, tuple[int, ...]]:
        """(monotonic time, counters) now."""
        self._admin.execute("SELECT pg_stat_clear_snapshot()")
        row = self._admin.execute(f"SELECT {', '.join(COUNTERS)} FROM pg_stat_database WHERE datname = %s",
                                  (self.name,)).fetchone()
        assert row is not None, f"no statistics for {self.name}"
        return time.monotonic(), tuple(int(value) for value in row)

    def rates(self, seconds: float) -> dict[str, float]:
        """Each counter's increase per second over the next `seconds`."""
        started, first = self.read()
        time.sleep(seconds)
        ended, last = self.read()
        names = ("transactions", "rows_returned", "rows_fetched", "rows_written")
        return {name: (b - a) / (ended - started) for name, a, b in zip(names, first, last, strict=True)}

    def close(self) -> None:
        self._admin.close()


@dataclass
class Outcome:
    """One server's figures."""

    code: Code
    users: int
    empty: dict[str, float] | None
    idle: dict[str, float]
    channels: int
    seconds_to_open: float
    ended: int
    messages_per_s: float
    load_cpu_share: float
    server_cpu_share: float
    load_average: tuple[float, float]


def prepare(tree: Path, robots: str, names: list[str], stack: ExitStack) -> str:
    """A fresh database (dropped when stack closes) migrated by tree's code, with the students."""
    database_url = stack.enter_context(fresh_database())
    create_students(database_url, names, tree, {"TELELAB_ROBOTS": robots, "TELELAB_SECRET_KEY": SECRET_KEY})
    return database_url


def prepare_all(servers: list[tuple[Code, Path]], robots: str, names: list[str], stack: ExitStack,
                pool: ThreadPoolExecutor) -> list[str]:
    """Each server's database: one per checkout prepared (at once), and a copy of it for each further server of that
    checkout (today's code serves two; preparing one is a process that imports the middleware and migrates)."""
    trees = list(dict.fromkeys(tree for _, tree in servers))
    prepared = dict(zip(trees, pool.map(lambda tree: prepare(tree, robots, names, stack), trees), strict=True))
    databases: list[str] = []
    given: set[Path] = set()
    for _, tree in servers:
        first = tree not in given
        given.add(tree)
        databases.append(prepared[tree] if first else stack.enter_context(fresh_database(copy_of=prepared[tree])))
    return databases


def measure(code: Code, tree: Path, database_url: str, robots: str, names: list[str], quick: bool) -> Outcome:
    """One server on its own database: nobody connected, then one idle console per student (held by a load process
    of its own)."""
    environment = {"TELELAB_ROBOTS": robots, "TELELAB_SECRET_KEY": SECRET_KEY, "TELELAB_DATABASE_URL": database_url}
    users = len(names)
    with ExitStack() as stack:
        load = LoadProcess(run_consoles)  # starts while the server does
        stack.callback(load.stop)
        server = WebServer(code.command, environment, tree)
        stack.callback(server.stop, 2)  # SIGINT: each server's own clean stop
        cookies = log_in(server.url, names)
        counters = DatabaseCounters(database_url)
        stack.callback(counters.close)
        time.sleep(SETTLE_QUICK_S if quick else SETTLE_S)
        empty = None if quick else counters.rates(EMPTY_S)
        opened = load.ask("open", (server.port, cookies, code.one_link), 180)
        time.sleep(SETTLE_QUICK_S if quick else SETTLE_S)
        window = WINDOW_QUICK_S if quick else WINDOW_S
        pid, average_before = server.worker_pids()[0], load_average()
        cpu_before = cpu_seconds(pid)
        load.commands.put(("idle", window))
        idle = counters.rates(window)
        idled = load.reports.get(timeout=60)[1]
        server_cpu = (cpu_seconds(pid) - cpu_before) / window
        outcome = Outcome(code, users, empty, idle, idled["channels"], opened["seconds"], idled["ended"],
                          idled["messages_per_s"], idled["cpu_share"], server_cpu, (average_before, load_average()))
    print(f"{code.key}: {idle['transactions']:.1f} transactions/s with {users} idle consoles "
          f"({empty['transactions'] if empty else float('nan'):.1f} with none), {outcome.channels} channels open, "
          f"load average "
          f"{outcome.load_average[1]:.2f}", flush=True)
    return outcome


# --- the report --------------------------------------------------------------------------------------------------

def _rows(outcomes: list[Outcome], quick: bool) -> list[Measurement]:
    floor = next((outcome for outcome in outcomes if outcome.code.key == "before"), None)
    rows = []
    for outcome in outcomes:
        scenario = f"{outcome.users} idle consoles, {outcome.code.scenario}"
        users = outcome.users
        compared = floor is not None and outcome is not floor

        def vs_floor(name: str, per_user: bool = False, compared: bool = compared) -> float | None:
            if floor is None or not compared:
                return None
            return floor.idle[name] / (floor.users if per_user else 1)

        note = (f"load average (1 min) {outcome.load_average[0]:.2f} -> {outcome.load_average[1]:.2f} over the "
                f"{'quick ' if quick else ''}window; server CPU {outcome.server_cpu_share * 100:.0f} % of a core, "
                f"load generator {outcome.load_cpu_share * 100:.1f} %")
        rows += [
            Measurement(scenario, "transactions/s reaching PostgreSQL (commits + rollbacks)",
                        outcome.idle["transactions"], "1/s", "-", vs_floor("transactions"),
                        note=note + ("; floor: before events" if compared else "")),
            Measurement(scenario, "transactions/s per idle user", outcome.idle["transactions"] / users, "1/s", "-",
                        vs_floor("transactions", per_user=True)),
            Measurement(scenario, "rows returned/s (tup_returned)", outcome.idle["rows_returned"], "1/s", "-",
                        vs_floor("rows_returned")),
            Measurement(scenario, "rows written/s (inserted + updated + deleted)", outcome.idle["rows_written"], "1/s",
                        "-", vs_floor("rows_written")),
            Measurement(scenario, "transactions/s with no console open",
                        outcome.empty["transactions"] if outcome.empty else None, "1/s", "-",
                        note="the same server, its users logged in, before the consoles opened"),
            Measurement(scenario, "channels open through the window", float(outcome.channels), "count",
                        f"= {2 * users}", passed=None if quick else outcome.channels == 2 * users and not outcome.ended,
                        note=f"{outcome.ended} sockets ended; messages to the consoles "
                             f"{outcome.messages_per_s:.1f}/s in all"),
        ]
    return rows


def run(quick: bool, output: Path, users: int | None = None) -> list[Measurement]:
    """Every server's figures, one after the other (their databases prepared together first); --quick runs the
    servers at once (each counts its own database, and a smoke run grades nothing)."""
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    users = users or (USERS_QUICK if quick else USERS_FULL)
    names = [f"idle{i}" for i in range(users)]
    robots = [SkillServerProcess(name, "empty", echo=False) for name in ROBOTS]
    with ExitStack() as stack:
        for robot in robots:
            robot.start()
            stack.callback(robot.stop)
        for robot in robots:
            wait_until_serving(robot.address)
        addresses = ",".join(f"{robot.name}={robot.address}" for robot in robots)
        servers = versions(extract_before(Path(stack.enter_context(tempfile.TemporaryDirectory(
            prefix="telelab-before-")))))
        with ThreadPoolExecutor(len(servers)) as pool:
            databases = prepare_all(servers, addresses, names, stack, pool)
            measured = [(code, tree, database_url, addresses, names, quick)
                        for (code, tree), database_url in zip(servers, databases, strict=True)]
            outcomes = (list(pool.map(lambda arguments: measure(*arguments), measured)) if quick
                        else [measure(*arguments) for arguments in measured])
    rows = _rows(outcomes, quick)
    print_table(f"Database load at {users} idle logged-in users (PostgreSQL, pg_stat_database)", rows)
    write_json(output / "database_load.json", rows, {"quick": quick, "users": users, "before_commit": BEFORE_COMMIT,
                                                     "window_s": WINDOW_QUICK_S if quick else WINDOW_S})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.database_load", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    parser.add_argument("--users", type=int, default=None, help=f"idle users (default {USERS_FULL})")
    args = parser.parse_args(argv)
    run(args.quick, args.output, args.users)
    return 0


if __name__ == "__main__":
    sys.exit(main())
