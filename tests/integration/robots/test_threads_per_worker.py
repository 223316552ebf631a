"""A web worker's threads do not grow with the robots its consoles watch: camera, telemetry and localization reach
each robot on the worker's asyncio loop (grpc.aio), not on a pump thread per stream (before: about 3 threads per
robot). Measured on `telelab web` in a child process, its threads read from /proc, with consoles (camera, telemetry,
localization and drive on one /ws/link each) open on 1 robot and then on 20 stand-in robots
(benchmarks/standin_robots.py: grpc.aio servers speaking the robot protocol, no pybullet)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from urllib.request import urlopen

import pytest

from benchmarks.standin_robots import StandInFleet
from benchmarks.web_tier import free_port
from middleware.access.liveness import PROBES_AT_ONCE
from middleware.live.loop import WORK_THREADS
from tests.conftest import STUDENT_PASSWORD, LabClient, add_test_account, make_test_app

ROBOTS = 20
STUDENTS = 4  # a user holds at most 40 sockets; a class has a student per robot, these share them
CHANNELS = ("camera", "telemetry", "localization", "drive")


def _threads(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError("no Threads line")


def _settled_threads(pid: int, window_s: float = 1.0) -> int:
    """The fewest threads over window_s: a handshake's request thread ends just after its socket is handed over."""
    least, deadline = _threads(pid), time.monotonic() + window_s
    while time.monotonic() < deadline:
        time.sleep(0.05)
        least = min(least, _threads(pid))
    return least


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int, StandInFleet]]:
    from middleware.db import session_factory
    from middleware.robots.registry import robot_registry

    fleet = StandInFleet(ROBOTS)
    tmp_path = tmp_path_factory.mktemp("threads")
    database_url = f"sqlite:///{tmp_path / 'web.sqlite3'}"
    app = make_test_app(database_url, fleet.robots_setting, tmp_path)
    with session_factory(app)() as session:
        for index in range(2, STUDENTS + 1):
            add_test_account(session, f"student{index}", "student")
        session.commit()
    robot_registry(app).close()
    port = free_port()
    env = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_ROBOTS": fleet.robots_setting,
           "TELELAB_SECRET_KEY": "threads-test", "PYTHONUNBUFFERED": "1",
           # The session recorder (middleware/recordings/, being built) still reads each open session on a thread
           # of its own plus a sync gRPC stream's spin thread: 2 a robot. Measured here without it until it reads
           # on the loop too (RobotLink.watch_telemetry); with it on, this test reports those threads.
           "TELELAB_RECORDINGS": os.environ.get("TELELAB_THREADS_TEST_RECORDINGS", "0")}
    with open(tmp_path / "web.log", "wb") as log:
        process = subprocess.Popen([sys.executable, "-m", "middleware.cli", "web", "--port", str(port)], env=env,
                                   cwd=Path(__file__).resolve().parents[3], stdout=subprocess.DEVNULL, stderr=log)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    try:
        while True:
            try:
                with urlopen(url + "/login", timeout=2):
                    break
            except OSError:
                assert process.poll() is None and time.monotonic() < deadline, (tmp_path / "web.log").read_text()
                time.sleep(0.2)
        yield url, process.pid, fleet
    finally:
        process.terminate()
        process.wait(15)
        fleet.stop()
        log_text = (tmp_path / "web.log").read_text()
        assert "Traceback" not in log_text, log_text


def _open_console(client: LabClient, robot: str):
    """One link carrying the console's robot channels, once each has delivered (drive: its ready)."""
    ws = client.websocket("/ws/link")
    for sub, channel in enumerate(CHANNELS, start=1):
        ws.send(json.dumps({"type": "subscribe", "sub": sub, "path": f"/ws/robots/{robot}/{channel}"}))
    waiting, deadline = set(range(1, len(CHANNELS) + 1)), time.monotonic() + 30
    while waiting:
        message = ws.receive(timeout=max(0.05, deadline - time.monotonic()))
        assert message is not None, f"{robot}: channels {sorted(waiting)} sent nothing"
        if isinstance(message, bytes):
            waiting.discard(int.from_bytes(message[:4], "big"))
            continue
        head, _, text = message.partition(" ")
        if head != "0" and json.loads(text).get("type") in {"telemetry", "localization", "ready"}:
            waiting.discard(int(head))
        assert '"closed"' not in text, text
    return ws


def test_threads_stay_flat_from_1_to_20_robots_with_consoles_open(lab: tuple[str, int, StandInFleet]) -> None:
    url, pid, fleet = lab
    clients = []
    for index in range(1, STUDENTS + 1):
        client = LabClient(url)
        assert client.login(f"student{index}", STUDENT_PASSWORD) == 302
        clients.append(client)
    names = list(fleet.addresses)
    idle = _settled_threads(pid)
    consoles = [_open_console(clients[0], names[0])]
    one = _settled_threads(pid)
    consoles += [_open_console(clients[i % STUDENTS], name) for i, name in enumerate(names[1:], start=1)]
    many = _settled_threads(pid)
    print(f"\nweb worker threads: {idle} idle, {one} with 1 robot's console, {many} with {ROBOTS} robots' consoles")
    # Before: 3 pump threads per robot (57 more for 19 robots). Now only the pools with fixed ceilings may grow: the
    # sockets' blocking work and the robots' liveness probes, and a request or two in flight.
    ceiling = WORK_THREADS + PROBES_AT_ONCE + 4
    assert many - one <= ceiling, f"{many - one} threads more for {ROBOTS - 1} robots more (ceiling {ceiling})"
    for ws in consoles:
        ws.close()
