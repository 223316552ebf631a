"""Event latency across web workers: two gunicorn workers (separate processes, two ports, as two hosts would be)
on one PostgreSQL database, one user on each. A chat message posted through one worker, until the other worker's
socket delivers it; a turn passed through one worker's queue socket, until the other user's socket on the other
worker shows control. The floor is the same with both users on the same worker, in the same run.

    python -m benchmarks.workers [--quick] [--output DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from urllib.parse import urlsplit

from benchmarks.lab_under_test import PASSWORD, Browser
from benchmarks.ports import free_port
from benchmarks.report import Measurement, percentile_ms, print_table, write_json
from middleware.chat.services import RATE_LIMIT_MESSAGES

POSTGRES_URL = os.environ.get("TELELAB_TEST_POSTGRES_URL", "postgresql+psycopg://postgres@127.0.0.1:5432/test")
P99_TARGET_MS = 50.0
WRITERS = 10  # chat takes 5 messages per 10 s from a user: the messages come from several writers in turn


@contextmanager
def _database() -> Iterator[str]:
    import psycopg

    name = f"telelab_bench_{uuid.uuid4().hex[:10]}"
    admin = psycopg.connect(POSTGRES_URL.replace("postgresql+psycopg://", "postgresql://", 1), autocommit=True)
    with admin:
        admin.execute(f'CREATE DATABASE "{name}"')
        try:
            yield urlsplit(POSTGRES_URL)._replace(path=f"/{name}").geturl()
        finally:
            admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


def _prepare(database_url: str) -> None:
    from unittest import mock

    from middleware import create_app
    from middleware.access.coordinator import access_coordinator
    from middleware.auth import services
    from middleware.auth.services import create_user
    from middleware.db import session_factory, upgrade_to_head

    upgrade_to_head(database_url)
    app = create_app({"DATABASE_URL": database_url, "ROBOTS": ()})
    # One scrypt hash for every user, computed once (web_tier.py); each login still checks one on the server.
    one_hash = services.hash_password(PASSWORD)
    with (session_factory(app)() as session,
          mock.patch.object(services, "generate_password_hash", lambda *_args, **_kwargs: one_hash)):
        for name in ("near", "far", *(f"writer{i}" for i in range(2 * WRITERS))):
            create_user(session, name, "student", PASSWORD)
        session.commit()
    access_coordinator(app).stop_ticker()
    session_factory(app).kw["bind"].dispose()


@contextmanager
def _workers(database_url: str, robot_address: str, count: int) -> Iterator[list[str]]:
    environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": "workers-benchmark",
                   "TELELAB_ROBOTS": f"lab-1={robot_address}"}
    ports = [free_port() for _ in range(count)]
    processes = [subprocess.Popen([sys.executable, "-m", "gunicorn", "-k", "gthread", "--threads", "50", "-w", "1",
                                   "-b", f"127.0.0.1:{port}", "--log-level", "warning", "middleware:create_app()"],
                                  env=environment) for port in ports]
    try:
        for port in ports:
            deadline = time.monotonic() + 60
            while True:
                try:
                    with socket.create_connection(("127.0.0.1", port), timeout=1):
                        break
                except OSError:
                    if time.monotonic() > deadline:
                        raise RuntimeError("a worker did not start") from None
                    time.sleep(0.2)
        yield [f"http://127.0.0.1:{port}" for port in ports]
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            process.wait(30)


def _next(ws, kind: str, timeout_s: float = 5.0, where=lambda _message: True) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        raw = ws.receive(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(raw, str):
            message = json.loads(raw)
            if message.get("type") == kind and where(message):
                return message
    raise RuntimeError(f"no {kind} message came")


def chat_latencies(writers: list[Browser], reader: Browser, count: int) -> list[float]:
    """From the start of a POST through a writer's worker to the message on reader's socket."""
    ws = reader.websocket("/ws/robots/lab-1/chat")
    try:
        _next(ws, "history")
        samples = []
        for i in range(count):
            body = f"event {uuid.uuid4().hex[:8]} {i}"
            started = time.perf_counter()
            status, _ = writers[i % len(writers)].post_json("/api/robots/lab-1/chat", {"body": body})
            if status != 201:
                raise RuntimeError(f"posting answered {status}")
            _next(ws, "message", where=lambda m, b=body: m["message"]["body"] == b)
            samples.append(time.perf_counter() - started)
            time.sleep(0.05)
        return samples
    finally:
        ws.close()


def _controller(sockets: list) -> int:
    """Which of the sockets' users holds control (read from their seats)."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        for index, ws in enumerate(sockets):
            raw = ws.receive(timeout=0.05)
            if isinstance(raw, str) and json.loads(raw).get("is_controller"):
                return index
    raise RuntimeError("nobody got control")


def turn_latencies(first: Browser, second: Browser, count: int) -> list[float]:
    """From a controller's "pass" on its queue socket to the other user's socket showing control."""
    sockets = [first.websocket("/ws/robots/lab-1/queue"), second.websocket("/ws/robots/lab-1/queue")]
    try:
        holder = _controller(sockets)
        samples = []
        for _ in range(count):
            other = 1 - holder
            started = time.perf_counter()
            sockets[holder].send(json.dumps({"type": "pass"}))
            _next(sockets[other], "queue", where=lambda m: m["is_controller"])
            samples.append(time.perf_counter() - started)
            holder = other
            time.sleep(0.05)
        return samples
    finally:
        for ws in sockets:
            ws.close()


def run(quick: bool, output: Path) -> list[Measurement]:
    from middleware.robots.processes import SkillServerProcess

    count = 5 if quick else 50
    robot = SkillServerProcess("lab-1", "empty", echo=False)
    robot.serve()
    try:
        with _database() as database_url:
            _prepare(database_url)
            with _workers(database_url, robot.address, 2) as urls:
                near, far, near_again = Browser(urls[0], "near"), Browser(urls[1], "far"), Browser(urls[0], "far")
                # As many writers as the chat's rate limit needs (RATE_LIMIT_MESSAGES each), at most WRITERS: each one
                # logs in (a password check); a writer per message made a quick run's ten logins take 7 of its 32 s.
                per_way = min(WRITERS, math.ceil(count / RATE_LIMIT_MESSAGES))
                writers = [Browser(urls[0], f"writer{i}") for i in range(2 * per_way)]
                across_chat = chat_latencies(writers[:per_way], far, count)
                same_chat = chat_latencies(writers[per_way:], near_again, count)
                across_turn = turn_latencies(near, far, count)
                same_turn = turn_latencies(near, near_again, count)
    finally:
        robot.stop()
    rows = []
    for event, across, same in (("chat message", across_chat, same_chat), ("turn passed", across_turn, same_turn)):
        scenario = f"{event} across workers (floor: both users on one worker)"
        p99 = percentile_ms(across, 99)
        rows += [Measurement(scenario, "p50", percentile_ms(across, 50), "ms", "-", floor=percentile_ms(same, 50)),
                 Measurement(scenario, "p99", p99, "ms", f"<= {P99_TARGET_MS:g}", floor=percentile_ms(same, 99),
                             passed=None if quick else p99 <= P99_TARGET_MS)]
    print_table("Events across two web workers on one PostgreSQL", rows)
    output.mkdir(parents=True, exist_ok=True)
    write_json(output / "workers.json", rows, {"samples": count})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
