"""Open consoles on one web worker: `telelab up --workers 1`, then 1 000 consoles that each hold one link
(/ws/link) subscribed to their robot's queue and chat, 100 of them also to its camera and telemetry. Measured
beside a floor from the same run (the same requests with no console open): the p50 and p99 of an ordinary request
(GET /api/robots/<name>, the state a page polls), the worker's threads and memory, the frames each streaming
console received, and the consoles that opened and stayed open.

    python -m benchmarks.consoles [--quick] [--output DIR] [--consoles N] [--streaming N]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import multiprocessing
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from benchmarks.ports import free_port
from benchmarks.report import Measurement, percentile_ms, print_table, write_json
from benchmarks.web_tier import create_students

if TYPE_CHECKING:
    from benchmarks.lab_under_test import Browser

USERS_FULL = 100  # each user has consoles open in several tabs (a class's students and their second screens)
CONSOLES_FULL, STREAMING_FULL = 1000, 100
REQUEST_P99_TARGET_MS = 100.0
ROBOTS = ("lab-1", "lab-2")


def _children(pid: int) -> list[int]:
    found = []
    for task in Path("/proc").glob("[0-9]*"):
        try:
            if int((task / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(task.name))
        except (OSError, ValueError, IndexError):
            continue
    return found


def _status(pid: int, field: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise AssertionError(f"no {field} for {pid}")


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Lab:
    """`telelab up --workers 1` on a database of its own, with USERS students."""

    def __init__(self, users: int) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="telelab-consoles-"))
        self.port = free_port(neighbours=2)
        self.url = f"http://127.0.0.1:{self.port}"
        environment = {**os.environ, "TELELAB_DATABASE_URL": f"sqlite:///{self.folder / 'lab.sqlite3'}",
                       "TELELAB_SECRET_KEY": "consoles-benchmark", "PYTHONUNBUFFERED": "1"}
        self.process = subprocess.Popen(
            [str(Path(sys.executable).parent / "telelab"), "up", "--workers", "1", "--robots", str(len(ROBOTS)),
             "--no-course-robots", "--no-demo-video", "--port", str(self.port)],
            env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert self.process.stdout is not None
        for line in self.process.stdout:
            if "Telelab is running" in line:
                break
        else:
            raise RuntimeError("the lab did not start")
        threading.Thread(target=self.process.stdout.read, daemon=True).start()  # keep its pipe drained
        self._wait_until_serving()
        self.usernames = [f"console{i}" for i in range(users)]
        # One scrypt hash for them all, computed once (web_tier.py); each login still checks one on the server.
        create_students(environment["TELELAB_DATABASE_URL"], self.usernames, environment={"TELELAB_ROBOTS": ""})

    def _wait_until_serving(self) -> None:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=1):
                    return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("the lab never answered")

    def worker_pid(self) -> int:
        launcher = Path(f"/proc/{self.process.pid}/cmdline").read_bytes()
        workers = [pid for pid in _children(self.process.pid)
                   if Path(f"/proc/{pid}/cmdline").read_bytes() == launcher]
        assert len(workers) == 1, workers
        return workers[0]

    def stop(self) -> None:
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(60)
        except subprocess.TimeoutExpired:
            self.process.kill()


# --- the consoles: one process, one asyncio loop, one TCP connection per console ----------------------------

async def _console(port: int, cookie: str, robot: str, streaming: bool, tally: dict, go_home: asyncio.Event) -> None:
    from wsproto import ConnectionType, WSConnection
    from wsproto.events import (
        AcceptConnection,
        BytesMessage,
        CloseConnection,
        Ping,
        RejectConnection,
        Request,
        TextMessage,
    )

    host = f"127.0.0.1:{port}"
    reader, writer = await asyncio.open_connection("127.0.0.1", port, limit=1 << 20)
    ws = WSConnection(ConnectionType.CLIENT)
    writer.write(ws.send(Request(host=host, target="/ws/link", extra_headers=[
        (b"cookie", cookie.encode()), (b"origin", f"http://{host}".encode())])))
    channels = ["queue", "chat"] + (["camera", "telemetry"] if streaming else [])
    counts = {name: 0 for name in channels}
    tally["consoles"].append(counts)
    first_fragment = True
    sub_of_fragment = 0

    async def read() -> None:
        nonlocal first_fragment, sub_of_fragment
        while True:
            data = await reader.read(1 << 16)
            if not data:
                tally["dropped"] += 1
                return
            ws.receive_data(data)
            for event in ws.events():
                if isinstance(event, AcceptConnection):
                    for sub, name in enumerate(channels, start=1):
                        writer.write(ws.send(TextMessage(json.dumps(
                            {"type": "subscribe", "sub": sub, "path": f"/ws/robots/{robot}/{name}"}))))
                elif isinstance(event, RejectConnection):
                    tally["refused"] += 1
                    return
                elif isinstance(event, TextMessage | BytesMessage):
                    if first_fragment:
                        head = event.data[:4] if isinstance(event.data, bytes) else event.data.split(" ", 1)[0]
                        sub_of_fragment = int.from_bytes(head, "big") if isinstance(head, bytes) else int(head)
                        if sub_of_fragment == 0 and '"subscribed"' in event.data:
                            tally["subscribed"] += 1
                    first_fragment = event.message_finished
                    if event.message_finished and 0 < sub_of_fragment <= len(channels):
                        counts[channels[sub_of_fragment - 1]] += 1
                elif isinstance(event, Ping):
                    writer.write(ws.send(event.response()))
                elif isinstance(event, CloseConnection):
                    tally["closed_by_server"].append(event.code)
                    return

    reading = asyncio.ensure_future(read())
    await go_home.wait()
    reading.cancel()
    writer.close()


def run_consoles(port: int, cookies: list[str], consoles: int, streaming: int, reports, commands) -> None:
    """A load process: opens the consoles, reports when they are subscribed, counts until told to report."""

    async def main() -> None:
        tally = {"consoles": [], "dropped": 0, "refused": 0, "subscribed": 0, "closed_by_server": []}
        go_home = asyncio.Event()
        loop = asyncio.get_running_loop()
        tasks = []
        started = time.perf_counter()
        for i in range(consoles):
            tasks.append(asyncio.ensure_future(_console(port, cookies[i % len(cookies)], ROBOTS[i % len(ROBOTS)],
                                                        i < streaming, tally, go_home)))
            if i % 50 == 49:
                await asyncio.sleep(0.05)  # a class arrives over seconds, not in one instant
        wanted = sum(4 if i < streaming else 2 for i in range(consoles))
        while tally["subscribed"] < wanted and time.perf_counter() - started < 120:
            await asyncio.sleep(0.1)
        reports.put(("open", {"seconds": time.perf_counter() - started, "subscribed": tally["subscribed"],
                              "wanted": wanted}))
        await loop.run_in_executor(None, commands.get)  # "count"
        for counts in tally["consoles"]:
            for name in counts:
                counts[name] = 0
        counted_at = time.perf_counter()
        await loop.run_in_executor(None, commands.get)  # "report"
        elapsed = time.perf_counter() - counted_at
        reports.put(("counts", {"elapsed_s": elapsed, "consoles": tally["consoles"], "dropped": tally["dropped"],
                                "refused": tally["refused"], "closed_by_server": tally["closed_by_server"]}))
        go_home.set()
        await asyncio.gather(*tasks, return_exceptions=True)

    asyncio.run(main())


# --- the measurement ----------------------------------------------------------------------------------------

def _request_latencies(browser: Browser, duration_s: float, rate_hz: float) -> tuple[list[float], int]:
    samples, errors = [], 0
    due = time.monotonic()
    end = due + duration_s
    while due < end:
        time.sleep(max(0.0, due - time.monotonic()))
        due += 1.0 / rate_hz
        started = time.perf_counter()
        try:
            status, _ = browser.get(f"/api/robots/{ROBOTS[len(samples) % len(ROBOTS)]}")
        except Exception:  # noqa: BLE001 - counted as an error
            status = 0
        samples.append(time.perf_counter() - started)
        errors += status != 200
    return samples, errors


def run(quick: bool, output: Path, consoles: int | None = None, streaming: int | None = None) -> list[Measurement]:
    consoles = consoles or (40 if quick else CONSOLES_FULL)
    streaming = streaming if streaming is not None else (4 if quick else STREAMING_FULL)
    users = min(USERS_FULL, max(1, consoles // 10))
    measure_s = 2.0 if quick else 30.0
    # Imported here, not above: the load process (spawned, it imports this module again) needs no middleware, whose
    # import cost it about 2 s of CPU before any console opened.
    from benchmarks.lab_under_test import Browser

    print(f"starting the lab and logging {users} users in", flush=True)
    lab = Lab(users)
    context = multiprocessing.get_context("spawn")
    reports, commands = context.Queue(), context.Queue()
    try:
        browsers = [Browser(lab.url, name) for name in lab.usernames]
        cookies = ["; ".join(f"{c.name}={c.value}" for c in browser.cookies) for browser in browsers]
        probe = browsers[0]
        worker = lab.worker_pid()
        floor, floor_errors = _request_latencies(probe, measure_s / 2, 20.0)
        floor_threads = _status(worker, "Threads")
        floor_rss_mb = _status(worker, "VmRSS") / 1024
        load = context.Process(target=run_consoles, args=(lab.port, cookies, consoles, streaming, reports, commands),
                               daemon=True)
        load.start()
        _, opened = reports.get(timeout=300)
        print(f"{opened['subscribed']} channels of {consoles} consoles open in {opened['seconds']:.1f} s; measuring "
              f"for {measure_s:.0f} s", flush=True)
        commands.put("count")
        cpu_before, wall_before = _cpu_s(worker), time.perf_counter()
        loaded, loaded_errors = _request_latencies(probe, measure_s, 20.0)
        cpu_share = (_cpu_s(worker) - cpu_before) / (time.perf_counter() - wall_before)
        threads = _status(worker, "Threads")
        rss_mb = _status(worker, "VmRSS") / 1024
        commands.put("report")
        _, counts = reports.get(timeout=120)
        load.join(60)
    finally:
        lab.stop()
    per_console = counts["consoles"]
    elapsed = counts["elapsed_s"]
    camera = [c["camera"] / elapsed for c in per_console if "camera" in c]
    telemetry = [c["telemetry"] / elapsed for c in per_console if "telemetry" in c]
    stayed = consoles - counts["dropped"] - counts["refused"] - len(counts["closed_by_server"])
    p99 = percentile_ms(loaded, 99)
    graded = not quick
    scenario = f"{consoles} consoles, {streaming} streaming"
    rows = [
        Measurement(scenario, "consoles open on one worker (one link each)", float(stayed), "count",
                    f"= {consoles}", passed=stayed == consoles if graded else None),
        Measurement(scenario, "channels subscribed", float(opened["subscribed"]), "count", f"= {opened['wanted']}",
                    passed=opened["subscribed"] == opened["wanted"] if graded else None),
        Measurement(scenario, "seconds until every console was subscribed", opened["seconds"], "s", "-"),
        Measurement(scenario, "ordinary request p50 (GET /api/robots/<name>; floor: no console open)",
                    percentile_ms(loaded, 50), "ms", "-", floor=percentile_ms(floor, 50)),
        Measurement(scenario, "ordinary request p99", p99, "ms", f"<= {REQUEST_P99_TARGET_MS:g}",
                    floor=percentile_ms(floor, 99), passed=p99 <= REQUEST_P99_TARGET_MS if graded else None),
        Measurement(scenario, "ordinary request errors", float(floor_errors + loaded_errors), "count", "= 0",
                    passed=floor_errors + loaded_errors == 0 if graded else None),
        Measurement(scenario, "worker threads (floor: no console open)", float(threads), "count", "-",
                    floor=float(floor_threads)),
        Measurement(scenario, "worker memory", rss_mb, "MB", "-", floor=floor_rss_mb),
        Measurement(scenario, "worker CPU (share of one core)", cpu_share, "cores", "-"),
        Measurement(scenario, "camera fps at the slowest streaming console (floor: their mean)",
                    min(camera) if camera else 0.0, "fps", "-", floor=statistics.mean(camera) if camera else None),
        Measurement(scenario, "telemetry messages/s at the slowest streaming console (floor: their mean)",
                    min(telemetry) if telemetry else 0.0, "Hz", "-",
                    floor=statistics.mean(telemetry) if telemetry else None),
    ]
    print_table(f"{consoles} open consoles on one web worker, {streaming} streaming camera and telemetry", rows)
    output.mkdir(parents=True, exist_ok=True)
    write_json(output / "consoles.json", rows, {"consoles": consoles, "streaming": streaming, "users": users,
                                                "closed_by_server": counts["closed_by_server"][:20]})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    parser.add_argument("--consoles", type=int, default=None)
    parser.add_argument("--streaming", type=int, default=None)
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output), args.consoles, args.streaming)
    return 0


if __name__ == "__main__":
    sys.exit(main())
