"""Back-pressure on the WebSocket channels, against the web server in a process of its own (as `telelab web`
runs it): a client flooding chat, queue or drive for 5 s leaves another user served, no backlog behind it, and
the process's memory where it was."""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from urllib.request import urlopen

import pytest
import simple_websocket

from benchmarks.ports import free_port
from tests.conftest import STUDENT_PASSWORD, LabClient, make_test_app
from tests.integration.lab.test_robot_channels import closed_with, receive_json

FLOOD_S = 5.0
QUIET_S = 2.0  # the machine's own p99 without a flood: a few hundred requests
FLOOD_RATE_PER_S = 5000
# Another user's p99 during a flood (the bound). Unbounded, a flood's backlog took 90 s; bounded, the
# other user's p99 measured 4.5-5.1 ms beside 4.8-5.5 ms without the flood.
P99_LIMIT_S = 0.100
BACKLOG_LIMIT_S = 2.0
MEMORY_WAIT_S = 60.0
FLOODERS = ("flooder-chat", "flooder-queue", "flooder-drive", "flooder-big", "flooder-fast")
CHANNELS = {"chat": "/ws/robots/lab-1/chat", "queue": "/ws/robots/lab-1/queue", "drive": "/ws/robots/lab-1/drive"}


@dataclass
class WebProcess:
    """`telelab web` in a child process, on a free loopback port."""

    url: str
    process: subprocess.Popen

    def rss_bytes(self) -> int:
        """The resident memory of the web process."""
        for line in Path(f"/proc/{self.process.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
        raise AssertionError("no VmRSS line")

    def cpu_s(self) -> float:
        """The CPU time the web process used so far."""
        fields = Path(f"/proc/{self.process.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def client(self, username: str) -> LabClient:
        """A logged-in client of the web process."""
        client = LabClient(self.url)
        assert client.login(username, STUDENT_PASSWORD) == 302
        return client


@pytest.fixture(scope="module")
def web_process(tmp_path_factory: pytest.TempPathFactory, skill_server_address: str) -> Iterator[WebProcess]:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.robots.registry import robot_registry

    tmp_path = tmp_path_factory.mktemp("web")
    database_url = f"sqlite:///{tmp_path / 'web.sqlite3'}"
    robots = f"lab-1={skill_server_address}"
    app = make_test_app(database_url, robots, tmp_path)
    with session_factory(app)() as session:
        for flooder in FLOODERS:  # one per test: a flooder is refused for a while after its flood
            create_user(session, flooder, "student", STUDENT_PASSWORD)
        session.commit()
    robot_registry(app).close()
    port = free_port()
    env = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_ROBOTS": robots,
           "TELELAB_SECRET_KEY": "back-pressure-test", "PYTHONUNBUFFERED": "1"}
    with open(tmp_path / "web.log", "wb") as log:  # the child keeps its own copy of the descriptor
        process = subprocess.Popen([sys.executable, "-m", "middleware.cli", "web", "--port", str(port)], env=env,
                                   cwd=Path(__file__).resolve().parents[3], stdout=subprocess.DEVNULL, stderr=log)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 30
    while True:
        try:
            with urlopen(url + "/login", timeout=2):
                break
        except OSError:
            assert process.poll() is None and time.monotonic() < deadline, (tmp_path / "web.log").read_text()
            time.sleep(0.2)
    try:
        yield WebProcess(url, process)
    finally:
        process.terminate()
        process.wait(10)
        log = (tmp_path / "web.log").read_text()
        assert "Traceback" not in log, log


def _start_flood(web: WebProcess, client: LabClient, kind: str) -> subprocess.Popen:
    ws_url = web.url.replace("http", "ws", 1) + CHANNELS[kind]
    return subprocess.Popen([sys.executable, "-m", "tests.integration.middleware.flood_client", ws_url,
                             client.cookie_header(), kind, str(FLOOD_S), str(FLOOD_RATE_PER_S)],
                            stdout=subprocess.PIPE, cwd=Path(__file__).resolve().parents[3])


def _request_s(client: LabClient) -> float:
    started = time.perf_counter()
    status, _, _ = client.request("GET", "/api/robots/lab-1/chat")
    assert status == 200
    return time.perf_counter() - started


def _p99_while(client: LabClient, wait: Callable[[], object]) -> float:
    """The 99th percentile of client's request times, requests sent one after another while wait() runs."""
    latencies: list[float] = []
    waiting = threading.Thread(target=wait)
    waiting.start()
    while waiting.is_alive():
        latencies.append(_request_s(client))
        time.sleep(0.005)
    return statistics.quantiles(latencies, n=100)[98]


def _answered_s(client: LabClient, kind: str) -> float:
    """How long a fresh socket of the channel takes to answer its first message."""
    started = time.monotonic()
    ws = client.websocket(CHANNELS[kind])
    first = receive_json(ws, timeout_s=10)
    if kind == "drive":
        assert first["type"] == "ready"
        ws.send(json.dumps({"type": "ping", "id": 1}))
        while receive_json(ws, timeout_s=10)["type"] != "pong":
            pass
    elif kind == "chat":
        assert first["type"] == "history"
        ws.send(json.dumps({"type": "say", "body": "still here"}))
        assert receive_json(ws, timeout_s=10)["type"] in {"sent", "error"}
    else:
        assert first["type"] == "queue"
        ws.send(json.dumps({"type": "pass"}))
        assert receive_json(ws, timeout_s=10)["type"] == "queue"
    ws.close()
    return time.monotonic() - started


def _rss_back_within(web: WebProcess, baseline: int, wait_s: float) -> tuple[int, float]:
    """The first RSS within 10 % of baseline (or the last one seen) and how long it took."""
    started = time.monotonic()
    while True:
        rss = web.rss_bytes()
        if rss <= baseline * 1.10 or time.monotonic() - started > wait_s:
            return rss, time.monotonic() - started
        time.sleep(0.2)


@pytest.mark.parametrize("kind", CHANNELS)
def test_a_flooding_client_is_closed_and_leaves_the_others_served(web_process: WebProcess, kind: str) -> None:
    flooder, other = web_process.client(f"flooder-{kind}"), web_process.client("student1")
    for _ in range(3):  # warm up: every thread pool, connection and import the flood will touch
        _answered_s(flooder, kind)
        _answered_s(other, kind)
        _request_s(other)
    baseline_rss = web_process.rss_bytes()
    quiet_p99 = _p99_while(other, lambda: time.sleep(QUIET_S))

    flood = _start_flood(web_process, flooder, kind)
    assert flood.stdout.readline().strip() == b"flooding"
    cpu_before = web_process.cpu_s()
    p99 = _p99_while(other, flood.wait)
    cpu_s = web_process.cpu_s() - cpu_before
    tally = json.loads(flood.communicate()[0])
    backlog_s = _answered_s(other, kind)  # the flooder itself is refused for a while
    rss, waited_s = _rss_back_within(web_process, baseline_rss, MEMORY_WAIT_S)

    print(f"\n{kind}: sent {tally['sent']} in {FLOOD_S} s ({tally['sent'] / FLOOD_S:.0f}/s) over "
          f"{tally['connections']} connections, closes {tally['closes']}; other user's p99 {p99 * 1000:.1f} ms "
          f"(without the flood {quiet_p99 * 1000:.1f} ms); a fresh socket answered {backlog_s:.2f} s after; "
          f"RSS {baseline_rss / 2**20:.1f} -> {rss / 2**20:.1f} MiB after {waited_s:.0f} s; web process CPU "
          f"{cpu_s:.1f} s during the flood")
    # Closed for the flood (1008), then refused at the handshake while cooling down (429); a connection that
    # flooded on past the closing frame may be cut off before it read it (1005).
    assert any(close.startswith("1008 ") for close in tally["closes"]), tally
    assert {close.split(" ")[0] for close in tally["closes"]} <= {"1008", "handshake", "1005"}, tally
    assert {close for close in tally["closes"] if close.startswith("handshake")} <= {"handshake 429"}, tally
    # The limit, or twice the machine's own p99 without the flood where a busy machine is slower than that anyway.
    assert p99 < max(P99_LIMIT_S, 2 * quiet_p99)
    assert backlog_s < BACKLOG_LIMIT_S
    assert rss <= baseline_rss * 1.10


def test_a_message_over_the_size_limit_closes_the_socket_with_1009(web_process: WebProcess) -> None:
    ws = web_process.client("flooder-big").websocket(CHANNELS["chat"])
    assert receive_json(ws)["type"] == "history"
    ws.send("x" * 5000)
    assert closed_with(ws) == 1009


def test_a_client_over_the_rate_reads_why_it_was_closed(web_process: WebProcess) -> None:
    ws = web_process.client("flooder-fast").websocket(CHANNELS["queue"])
    assert receive_json(ws)["type"] == "queue"
    for _ in range(100):
        ws.send(json.dumps({"type": "join"}))
    with pytest.raises(simple_websocket.ConnectionClosed) as closed:
        for _ in range(50):
            ws.receive(timeout=0.2)
    assert closed.value.reason == 1008 and "at most 10 a second" in closed.value.message
