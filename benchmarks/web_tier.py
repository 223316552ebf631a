"""The web tier as the scaling benchmarks run it: a fresh PostgreSQL database, students, their logins, and a real
server process (`telelab up --workers N`, or a given command in a given checkout) with its workers' CPU."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from http.cookiejar import CookieJar
from pathlib import Path
from urllib.error import HTTPError
from urllib.parse import urlencode, urlsplit
from urllib.request import HTTPCookieProcessor, HTTPRedirectHandler, OpenerDirector, Request, build_opener

from benchmarks.ports import free_port

ROOT = Path(__file__).resolve().parents[1]
POSTGRES_URL = os.environ.get("TELELAB_TEST_POSTGRES_URL", "postgresql+psycopg://postgres@127.0.0.1:5432/test")
SECRET_KEY = "web-tier-benchmark"
PASSWORD = "benchmark-password"
CSRF_FIELD = re.compile(r'name="csrf_token"[^>]*value="([^"]+)"')

# Run in the checkout whose code is measured (the present one, or an older commit's). Every student gets the same
# scrypt hash of PASSWORD, computed once: hashing per student would take minutes for thousands; each login still
# checks a scrypt hash on the server, as it does in use.
_CREATE_STUDENTS = """
import sys
import middleware.auth.services as services
from middleware import create_app
from middleware.db import session_factory, upgrade_to_head
url, password, course_code, tutor_name, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
upgrade_to_head(url)
one_hash = services.generate_password_hash(password, method=services.PASSWORD_METHOD)
services.generate_password_hash = lambda *_args, **_kwargs: one_hash
app = create_app({"DATABASE_URL": url})
with session_factory(app)() as session:
    for name in names:
        services.create_user(session, name, "student", password)
    session.commit()
    if course_code:  # the tutor creates the course and enrols the students, through the courses' services
        from sqlalchemy import select
        from middleware.courses import services as courses
        from middleware.courses.schemas import CourseSettings
        from middleware.models import Course, User
        tutor = (session.scalar(select(User).where(User.username == tutor_name))
                 or services.create_user(session, tutor_name, "tutor", password))
        course = (session.scalar(select(Course).where(Course.code == course_code.upper()))
                  or courses.create_course(session, tutor, course_code, "A class day", CourseSettings()))
        for name in names:
            courses.enrol(session, tutor, course.id, name)
        session.commit()
print("created", len(names), flush=True)
import os
os._exit(0)  # the app's background threads need no goodbye
"""


def load_average() -> float:
    """The machine's 1-minute load average now."""
    return os.getloadavg()[0]


def machine_ticks() -> tuple[int, int]:
    """(all, idle) CPU time of the whole machine so far, in clock ticks, from /proc/stat."""
    values = [int(value) for value in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return sum(values), values[3] + values[4]  # idle + iowait


def busy_share(before: tuple[int, int], after: tuple[int, int]) -> float:
    """The share of all cores that were busy between two machine_ticks() readings (whoever used them)."""
    total = after[0] - before[0]
    return 1.0 - (after[1] - before[1]) / total if total else 0.0


def cpu_seconds(pid: int) -> float:
    """User plus system CPU time of a process so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def children(pid: int) -> list[int]:
    """The processes whose parent is pid."""
    found = []
    for task in Path("/proc").glob("[0-9]*"):
        try:
            if int((task / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(task.name))
        except (OSError, ValueError, IndexError):
            continue
    return found


@contextmanager
def fresh_database(copy_of: str | None = None) -> Iterator[str]:
    """A new PostgreSQL database on the benchmark server (TELELAB_TEST_POSTGRES_URL), dropped on leaving: empty, or a
    copy of the database at copy_of (nobody may be connected to that one meanwhile)."""
    import psycopg

    name = f"telelab_bench_{uuid.uuid4().hex[:10]}"
    template = f' TEMPLATE "{urlsplit(copy_of).path.lstrip("/")}"' if copy_of else ""
    with psycopg.connect(admin_dsn(), autocommit=True) as admin:
        admin.execute(f'CREATE DATABASE "{name}"{template}')
        try:
            yield urlsplit(POSTGRES_URL)._replace(path=f"/{name}").geturl()
        finally:
            admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


def admin_dsn() -> str:
    """The libpq address of the server's administrative database (not one a benchmark measures)."""
    return POSTGRES_URL.replace("postgresql+psycopg://", "postgresql://", 1)


def create_students(database_url: str, names: list[str], code_root: Path = ROOT,
                    environment: dict[str, str] | None = None, course_code: str = "", tutor: str = "") -> None:
    """Migrates the database with code_root's code and adds the students (password PASSWORD); with course_code, also
    the tutor (the same password), who creates that course and enrols the students."""
    for start in range(0, len(names), 2000):  # the command line stays short
        subprocess.run([sys.executable, "-c", _CREATE_STUDENTS, database_url, PASSWORD, course_code, tutor,
                        *names[start:start + 2000]],
                       cwd=code_root, env={**os.environ, **(environment or {})}, check=True, capture_output=True)


class _NoRedirect(HTTPRedirectHandler):
    def redirect_request(self, *_args, **_kwargs):
        return None


def log_in_one(base_url: str, name: str) -> str:
    """The student logs in through the login page (its form, its CSRF token); returns the Cookie header."""
    return cookie_header(logged_in(base_url, name)[1])


def cookie_header(cookies: CookieJar) -> str:
    """The Cookie header of what cookies hold now."""
    return "; ".join(f"{cookie.name}={cookie.value}" for cookie in cookies)


def logged_in(base_url: str, name: str) -> tuple[OpenerDirector, CookieJar]:
    """The user logs in through the login page (its form, its CSRF token); an opener that keeps their session (and
    follows no redirect), and its cookies."""
    cookies = CookieJar()
    opener = build_opener(HTTPCookieProcessor(cookies), _NoRedirect())
    with opener.open(base_url + "/login", timeout=60) as page:
        token = CSRF_FIELD.search(page.read().decode()).group(1)
    form = urlencode({"username": name, "password": PASSWORD, "csrf_token": token}).encode()
    try:
        opener.open(Request(base_url + "/login", data=form, method="POST"), timeout=60).close()
        raise RuntimeError(f"{name} was not logged in (no redirect)")
    except HTTPError as answer:  # the redirect to the lab, which is not followed
        if answer.code != 302:
            raise RuntimeError(f"{name} could not log in ({answer.code})") from None
    return opener, cookies


def log_in(base_url: str, names: list[str], parallel: int = 8) -> list[str]:
    """Each student logs in through the login page; returns their Cookie headers, in order."""
    with ThreadPoolExecutor(parallel) as pool:
        return list(pool.map(lambda name: log_in_one(base_url, name), names))


class WebServer:
    """A web server process on a free loopback port, run from code_root, until stop()."""

    def __init__(self, command: list[str], environment: dict[str, str], code_root: Path = ROOT,
                 ready_line: str | None = None, port: int | None = None) -> None:
        self.port = port or free_port(neighbours=2)  # `telelab up` takes the next one for its demo LMS
        self.url = f"http://127.0.0.1:{self.port}"
        command = [part.replace("{port}", str(self.port)) for part in command]
        self.process = subprocess.Popen(command, cwd=code_root, env={**os.environ, "PYTHONUNBUFFERED": "1",
                                                                     **environment},
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert self.process.stdout is not None
        self.output: list[str] = []
        if ready_line is not None:
            for line in self.process.stdout:
                self.output.append(line)
                if ready_line in line:
                    break
            else:
                raise RuntimeError("the server did not start:\n" + "".join(self.output[-30:]))
        threading.Thread(target=self._keep_output, daemon=True).start()  # its pipe must not fill
        self._wait_until_serving()

    def _keep_output(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.output = [*self.output[-200:], line]

    def _wait_until_serving(self) -> None:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError("the server ended:\n" + "".join(self.output[-30:]))
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=1):
                    return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("the server never answered")

    def worker_pids(self) -> list[int]:
        """The server's gunicorn workers (forks with the launcher's command line); the process itself if none."""
        launcher = Path(f"/proc/{self.process.pid}/cmdline").read_bytes()
        workers = [pid for pid in children(self.process.pid)
                   if Path(f"/proc/{pid}/cmdline").read_bytes() == launcher]
        return workers or [self.process.pid]

    def wait_for_workers(self, count: int) -> list[int]:
        """Waits until count workers run and the server answers; returns their pids."""
        deadline = time.monotonic() + 60
        while len(pids := self.worker_pids()) != count or pids == [self.process.pid]:
            if time.monotonic() > deadline:
                raise RuntimeError(f"{count} workers never ran (found {pids})")
            time.sleep(0.2)
        time.sleep(0.5)  # each worker builds its app after the fork
        return pids

    def stop(self, how: int = signal.SIGINT) -> None:
        """Stops the server (SIGINT: `telelab up` then stops its robots too)."""
        if self.process.poll() is None:
            self.process.send_signal(how)
        try:
            self.process.wait(60)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(10)


def telelab_up(database_url: str, workers: int, robots: int = 1) -> WebServer:
    """`telelab up --workers N` on database_url, with `robots` lab robots and nothing else (no course robots, no
    demo video); its workers are running when this returns."""
    command = [str(Path(sys.executable).parent / "telelab"), "up", "--workers", str(workers), "--robots",
               str(robots), "--no-course-robots", "--no-demo-video", "--port", "{port}"]
    server = WebServer(command, {"TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": SECRET_KEY},
                       ready_line="Telelab is running")
    server.wait_for_workers(workers)
    return server
