"""The class-day benchmark's web host around the workers: Debian's nginx in front of them, and the meters of what
they spend (CPU of every worker and its children across a rolling restart, threads) and of PostgreSQL's transactions."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import threading
import time
from pathlib import Path

from benchmarks.web_tier import ROOT, WebServer, admin_dsn, cpu_seconds, free_port

NGINX = shutil.which("nginx") or "/usr/sbin/nginx"


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


def _answers(port: int) -> bool:
    import socket

    try:
        with socket.create_connection(("127.0.0.1", port), timeout=0.5):
            return True
    except OSError:
        return False


def settled_threads(pid: int, window_s: float = 1.0) -> int:
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


def database_transactions(database_url: str) -> int:
    import psycopg

    name = database_url.rsplit("/", 1)[1]
    with psycopg.connect(admin_dsn(), autocommit=True) as admin:
        admin.execute("SELECT pg_stat_clear_snapshot()")
        row = admin.execute("SELECT xact_commit + xact_rollback FROM pg_stat_database WHERE datname = %s",
                            (name,)).fetchone()
    return int(row[0]) if row else 0
