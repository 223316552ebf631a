"""Fixtures shared by the whole suite: databases, a running skill server, the app, a live server."""

from __future__ import annotations

import json
import os
import re
import secrets
import shutil
import tempfile
import threading
import uuid
import weakref
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from http.cookiejar import CookieJar
from pathlib import Path
from urllib.parse import urlencode, urlsplit
from urllib.request import HTTPCookieProcessor, HTTPRedirectHandler, Request, build_opener

import pytest

from tests import shared_templates, shared_url_builders

shared_url_builders.install()
shared_templates.install()

POSTGRES_SERVER_URL = os.environ.get("TELELAB_TEST_POSTGRES_URL", "postgresql+psycopg://postgres@127.0.0.1:5432/test")
STUDENT_PASSWORD = "correct-horse-battery"


def _postgres_admin_dsn() -> str:
    return POSTGRES_SERVER_URL.replace("postgresql+psycopg://", "postgresql://", 1)


def _postgres_admin():
    """An autocommit connection to the PostgreSQL server, for creating and dropping databases."""
    import psycopg

    if os.environ.get("TELELAB_SKIP_POSTGRES") == "1":
        pytest.skip("TELELAB_SKIP_POSTGRES=1: PostgreSQL tests skipped on purpose")
    try:
        return psycopg.connect(_postgres_admin_dsn(), autocommit=True, connect_timeout=5)
    except psycopg.OperationalError as error:
        pytest.fail(f"PostgreSQL at {POSTGRES_SERVER_URL} is not reachable ({error}); "
                    "start it or set TELELAB_SKIP_POSTGRES=1 to skip these tests knowingly.")


def _postgres_url(name: str) -> str:
    return urlsplit(POSTGRES_SERVER_URL)._replace(path=f"/{name}").geturl()


# Databases postgres_database() made and nobody has migrated yet: migrate_to_head may replace them by a copy.
_untouched_postgres: set[str] = set()


class _DatabasesMadeAhead:
    """PostgreSQL databases made, and dropped, by a thread of this process while its tests run: a CREATE DATABASE
    takes about half a second of the server's writing (the copy goes through its WAL and is synced), which each test
    on PostgreSQL waited for twice (an empty database, then a migrated copy). One of each kind is kept ready: empty
    (`template` None) or a copy of a template database."""

    def __init__(self) -> None:
        from concurrent.futures import ThreadPoolExecutor

        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="databases-made-ahead")
        self._ready: dict[str | None, object] = {}
        self._lock = threading.Lock()

    def take(self, template: str | None) -> str:
        """A database of that kind, nobody connected to it, and the next one started."""
        with self._lock:
            ready = self._ready.pop(template, None)
            self._ready[template] = self._thread.submit(self._make, template)
        return self._make(template) if ready is None else ready.result()  # type: ignore[attr-defined]

    def drop(self, name: str) -> None:
        self._thread.submit(self._drop, name)

    def close(self) -> None:
        """Drops the databases still kept ready, after the drops asked for; returns once all are done."""
        with self._lock:
            for ready in self._ready.values():
                with suppress(Exception):
                    self.drop(ready.result())  # type: ignore[attr-defined]
            self._ready.clear()
        self._thread.shutdown(wait=True)

    @staticmethod
    def _make(template: str | None) -> str:
        import psycopg

        name = f"telelab_test_{uuid.uuid4().hex[:12]}"
        with psycopg.connect(_postgres_admin_dsn(), autocommit=True, connect_timeout=5) as admin:
            admin.execute(f'CREATE DATABASE "{name}"' + (f' TEMPLATE "{template}"' if template else ""))
        return name

    @staticmethod
    def _drop(name: str) -> None:
        import psycopg

        with psycopg.connect(_postgres_admin_dsn(), autocommit=True, connect_timeout=5) as admin:
            admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


_made_ahead: _DatabasesMadeAhead | None = None


def _databases_made_ahead() -> _DatabasesMadeAhead:
    global _made_ahead
    if _made_ahead is None:
        _postgres_admin().close()  # the server answers, or the test fails (or skips) saying why
        _made_ahead = _DatabasesMadeAhead()
    return _made_ahead


@contextmanager
def postgres_database() -> Iterator[str]:
    """A new, empty PostgreSQL database, dropped on leaving."""
    made_ahead = _databases_made_ahead()
    name = made_ahead.take(template=None)
    _untouched_postgres.add(name)
    try:
        yield _postgres_url(name)
    finally:
        _untouched_postgres.discard(name)
        made_ahead.drop(name)


# What the real migrations built once in this pytest session, copied for every new database instead of migrating
# it again: "sqlite" is a migrated SQLite file, "postgresql" a migrated template database. Removed at the end.
_migrated_templates: dict[str, str] = {}


def _migrated_sqlite_template() -> Path:
    from middleware.db import upgrade_to_head

    if "sqlite" not in _migrated_templates:
        template = Path(tempfile.mkdtemp(prefix="telelab-migrated-")) / "template.sqlite3"
        upgrade_to_head(f"sqlite:///{template}")
        _migrated_templates["sqlite"] = str(template)
    return Path(_migrated_templates["sqlite"])


def _migrated_postgres_template(admin) -> str:
    from middleware.db import upgrade_to_head

    if "postgresql" not in _migrated_templates:
        name = f"telelab_test_template_{uuid.uuid4().hex[:12]}"
        admin.execute(f'CREATE DATABASE "{name}"')
        try:
            upgrade_to_head(_postgres_url(name))  # Alembic's engine uses NullPool: no connection is left open
        except BaseException:
            admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
            raise
        _migrated_templates["postgresql"] = name
    return _migrated_templates["postgresql"]


def migrate_to_head(database_url: str) -> None:
    """What upgrade_to_head(database_url) does, faster for a new database: a SQLite file not created yet becomes a
    copy of a file migrated once per session, and a database postgres_database() just made is replaced by a copy of a
    template database migrated once per session (Alembic takes about 0.25 s per SQLite database). Any other
    database is migrated for real. Tests of the migrations themselves call upgrade_to_head."""
    from middleware.db import upgrade_to_head

    if database_url.startswith("sqlite:///") and not database_url.startswith("sqlite:///:memory:"):
        path = Path(database_url.removeprefix("sqlite:///"))
        if not path.exists():
            template = _migrated_sqlite_template()
            path.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(template, path)
            return
    name = urlsplit(database_url).path.lstrip("/")
    if database_url.startswith("postgresql") and name in _untouched_postgres:
        with _postgres_admin() as admin:
            copy = _databases_made_ahead().take(template=_migrated_postgres_template(admin))
            admin.execute(f'DROP DATABASE "{name}"')  # fails, rather than hides it, if someone is connected
            admin.execute(f'ALTER DATABASE "{copy}" RENAME TO "{name}"')
        _untouched_postgres.discard(name)
        return
    upgrade_to_head(database_url)


def _drop_migrated_templates() -> None:
    if _made_ahead is not None:
        _made_ahead.close()  # its copies first: a template cannot be dropped while one is being made from it
    sqlite_template = _migrated_templates.pop("sqlite", None)
    if sqlite_template is not None:
        shutil.rmtree(Path(sqlite_template).parent, ignore_errors=True)
    postgres_template = _migrated_templates.pop("postgresql", None)
    if postgres_template is not None:
        import sys

        import psycopg

        try:
            with psycopg.connect(_postgres_admin_dsn(), autocommit=True, connect_timeout=5) as admin:
                admin.execute(f'DROP DATABASE IF EXISTS "{postgres_template}" WITH (FORCE)')
        except psycopg.Error as error:
            print(f"\nThe template database {postgres_template} could not be dropped: {error}", file=sys.stderr)


@pytest.fixture
def postgres_url() -> Iterator[str]:
    """A new, empty PostgreSQL database for one test, dropped afterwards."""
    with postgres_database() as url:
        yield url


DATABASES = ["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)]


@pytest.fixture(params=DATABASES)
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """An empty database URL, once on SQLite and once on PostgreSQL."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'telelab.sqlite3'}"
    return request.getfixturevalue("postgres_url")


@pytest.fixture(scope="module", params=DATABASES)
def module_database_url(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """An empty database URL shared by one module's tests, once on SQLite and once on PostgreSQL."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path_factory.mktemp('db') / 'telelab.sqlite3'}"
        return
    with postgres_database() as url:
        yield url


@pytest.fixture
def engine(database_url: str):
    """An engine on that database, migrated to the head revision."""
    from middleware.db import make_engine

    migrate_to_head(database_url)
    made = make_engine(database_url)
    yield made
    made.dispose()


@pytest.fixture(scope="session")
def skill_server_address() -> Iterator[str]:
    """A real skill server (real-time, default scene) as a child process, shared by the session."""
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    robot = SkillServerProcess("lab-1", "lab")
    robot.start()
    try:
        wait_until_serving(robot.address)
        yield robot.address
    finally:
        robot.stop()


# Passwords hashed in the suite's own processes use scrypt at N=1024, not the product's 32768: a login checks a
# password with the parameters its hash carries, so every login takes the product's own path at a fiftieth of its
# CPU (2 ms, not 100 ms; the suite logs in and fails logins thousands of times: at N=4096, 34 CPU-s of a run's
# pytest processes). Labs the suite starts as processes of their own (`telelab up`, the benchmarks) keep the
# product's cost, which test_password_cost.py checks.
TEST_PASSWORD_METHOD = "scrypt:1024:8:1"


@pytest.fixture(scope="session", autouse=True)
def product_password_method() -> Iterator[str]:
    """The product's password hash method, while the suite's processes hash at TEST_PASSWORD_METHOD."""
    from unittest import mock

    from middleware.auth import services

    product = services.PASSWORD_METHOD
    with mock.patch.object(services, "PASSWORD_METHOD", TEST_PASSWORD_METHOD):
        yield product


# The hash of STUDENT_PASSWORD per test account, made once per session by the product's own hash_password; per
# username, so that two accounts of one test never share a hash, as with create_user.
_student_password_hashes: dict[str, str] = {}


def add_test_account(session, username: str, role: str):
    """An account (a User, flushed) with STUDENT_PASSWORD, as create_user(session, username, role, STUDENT_PASSWORD)
    makes it, without hashing the password again in every test. Tests of create_user itself call create_user."""
    from middleware.auth.schemas import clean_role, clean_username
    from middleware.auth.services import hash_password
    from middleware.models import User

    name = clean_username(username)
    if name not in _student_password_hashes:
        _student_password_hashes[name] = hash_password(STUDENT_PASSWORD)
    user = User(username=name, role=clean_role(role).value, password_hash=_student_password_hashes[name])
    session.add(user)
    session.flush()
    return user


def make_test_app(database_url: str, robots: str, tmp_path: Path):
    """The app on a migrated database with a known student account."""
    from middleware import create_app
    from middleware.config import parse_robots
    from middleware.db import session_factory

    migrate_to_head(database_url)
    app = create_app({
        "DATABASE_URL": database_url,
        "SECRET_KEY": secrets.token_hex(16),
        "ROBOTS": parse_robots(robots),
        "TESTING": True,
    })
    app.instance_path = str(tmp_path / "instance")
    with session_factory(app)() as session:
        add_test_account(session, "student1", "student")
        session.commit()
    return app


def _let_go(application) -> None:
    """Stops what a test app started: its ticker, its links, and its farm's robots (a lab's robots outlive its web
    process by design, so the practice robots of a test would otherwise run on after the suite)."""
    from middleware.access.coordinator import access_coordinator
    from middleware.farm.setup import robot_farm
    from middleware.robots.registry import robot_registry
    from middleware.teaching.practice_robots import practice_manager

    access_coordinator(application).close()
    practice_manager(application).close()  # its keeper would otherwise query a database the test has dropped
    robot_registry(application).close()
    robot_farm(application).close()


@pytest.fixture
def app(tmp_path: Path, skill_server_address: str):
    """The middleware on SQLite, wired to the session's skill server."""
    application = make_test_app(f"sqlite:///{tmp_path / 'app.sqlite3'}",
                                f"lab-1={skill_server_address},ghost=127.0.0.1:9", tmp_path)
    yield application
    _let_go(application)


class LiveServer:
    """The app served on a free loopback port by the same threaded server `telelab web` uses."""

    def __init__(self, app) -> None:
        from middleware.serve import make_threaded_server

        self._server = make_threaded_server(app, "127.0.0.1", 0)
        self.app = app
        self.url = f"http://127.0.0.1:{self._server.server_port}"
        # shutdown() waits for the serving loop to look up (every 0.5 s by default: 0.25 s per test on average);
        # a request wakes the loop at once either way.
        self._thread = threading.Thread(target=self._server.serve_forever, kwargs={"poll_interval": 0.05},
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stops serving."""
        self._server.shutdown()
        self._server.server_close()


@contextmanager
def served_lab(robots: str, tmp_path: Path) -> Iterator[LiveServer]:
    """The app on a fresh SQLite database with student1 and tutor1, wired to robots ('name=host:port,...'), served."""
    from middleware.db import session_factory

    application = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", robots, tmp_path)
    with session_factory(application)() as session:
        add_test_account(session, "tutor1", "tutor")
        session.commit()
    server = LiveServer(application)
    try:
        yield server
    finally:
        server.stop()
        _let_go(application)


def make_course(app, code: str, members: dict[str, str]) -> int:
    """A course with the given members ({username: "tutor" | "student"}); its id. Tutors act only on the courses
    they teach and on those courses' students (middleware/README.md, "Authorization table")."""
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User

    with session_factory(app)() as session:
        course = Course(code=code, title=f"Course {code}")
        session.add(course)
        session.flush()
        users = session.query(User).filter(User.username.in_(members))
        session.add_all(CourseMembership(course_id=course.id, user_id=u.id, role=members[u.username]) for u in users)
        session.commit()
        return course.id


def ready_for_trials(app_or_session, username: str, order_index: int = 1) -> None:
    """username has answered the experiment's participant questions (declined) and finished the learning period,
    and runs row order_index of the design (row 1 begins with 1 s, preview on; row 0 with the no-delay control)."""
    from datetime import UTC, datetime, timedelta

    from sqlalchemy.orm import Session

    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.experiment import Participant

    def write(session: Session) -> None:
        user = session.query(User).filter_by(username=username).one()
        now = datetime.now(UTC)
        session.merge(Participant(user_id=user.id, consent=False, answered_at=now,
                                  learning_started_at=now - timedelta(days=1), order_index=order_index))
        session.flush()

    if isinstance(app_or_session, Session):
        write(app_or_session)
        return
    with session_factory(app_or_session)() as session:
        write(session)
        session.commit()


@pytest.fixture
def live_server(app) -> Iterator[LiveServer]:
    """A running web server for the app."""
    server = LiveServer(app)
    yield server
    server.stop()


_clients_with_sockets: weakref.WeakSet[LabClient] = weakref.WeakSet()


@pytest.fixture(autouse=True)
def _close_test_sockets() -> Iterator[None]:
    """Every WebSocket a test opened through a LabClient is closed when the test ends, passed or failed."""
    yield
    for client in list(_clients_with_sockets):
        client.close()


class LabClient:
    """A browser-like HTTP client with cookies and CSRF tokens, and WebSockets carrying the session."""

    CSRF_FIELD = re.compile(r'name="csrf_token"[^>]*value="([^"]+)"')

    def __init__(self, base_url: str) -> None:
        self.base_url = base_url
        self.cookies = CookieJar()
        self._opener = build_opener(HTTPCookieProcessor(self.cookies), _NoRedirect())
        self._sockets: list = []

    def close(self) -> None:
        """Closes every WebSocket this client opened, so that a failed test leaves no reader thread behind."""
        for socket in self._sockets:
            with suppress(Exception):  # already closed by the server or the test
                socket.close()
        self._sockets.clear()

    def request(self, method: str, path: str, form: dict[str, str] | None = None,
                headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], str]:
        """(status, headers, body) of one request; redirects are returned, not followed."""
        data = urlencode(form).encode() if form is not None else None
        request = Request(self.base_url + path, data=data, method=method, headers=headers or {})
        try:
            with self._opener.open(request, timeout=30) as response:
                return response.status, dict(response.headers), response.read().decode()
        except Exception as error:  # urllib raises for 4xx/5xx; they are answers here
            if hasattr(error, "code"):
                return error.code, dict(error.headers), error.read().decode()
            raise

    def csrf_token(self, path: str = "/login") -> str:
        """The CSRF token in the form at path."""
        _, _, body = self.request("GET", path)
        match = self.CSRF_FIELD.search(body)
        assert match, f"no csrf_token field on {path}"
        return match.group(1)

    def login(self, username: str = "student1", password: str = STUDENT_PASSWORD) -> int:
        """Logs in through the form; returns the status of the POST."""
        token = self.csrf_token()
        status, _, _ = self.request("POST", "/login", {"username": username, "password": password,
                                                      "csrf_token": token})
        return status

    def cookie_header(self) -> str:
        """The Cookie header a browser would send."""
        return "; ".join(f"{c.name}={c.value}" for c in self.cookies)

    def websocket(self, path: str, origin: str | None = None):
        """A WebSocket to path carrying this client's session cookie."""
        from benchmarks.lab_under_test import WebSocketClient

        headers = {"Cookie": self.cookie_header()}
        if origin is not None:
            headers["Origin"] = origin
        socket = WebSocketClient.connect(self.base_url.replace("http", "ws", 1) + path, headers=headers)
        self._sockets.append(socket)
        _clients_with_sockets.add(self)
        return socket


class _NoRedirect(HTTPRedirectHandler):
    """Hands redirects back as answers instead of following them."""

    def redirect_request(self, *_args, **_kwargs):
        return None


@pytest.fixture
def lab_client(live_server: LiveServer) -> LabClient:
    """A client of the live server, not logged in."""
    return LabClient(live_server.url)


@pytest.fixture
def student_client(lab_client: LabClient) -> LabClient:
    """A client of the live server, logged in as the student."""
    assert lab_client.login() == 302
    return lab_client


# Playwright's own choice for headless runs is Chromium's headless shell, and so is the suite's: Debian's
# chromium-headless-shell, the same Chromium release as the chromium package without the full browser's windows (the
# full one starts top-chrome renderers for each context: in the class and turn journeys the browser's CPU was 23.6 s
# against 14.2 s). A test of the full browser's own policies (its third-party cookie setting) launches
# CHROMIUM_BROWSER_PATH, as the benchmarks do.
CHROMIUM_PATH = "/usr/bin/chromium-headless-shell"
CHROMIUM_BROWSER_PATH = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]
ARTIFACTS_DIR = Path(__file__).resolve().parent.parent / "test-artifacts"


@pytest.fixture(scope="session")
def chromium():
    """Debian's Chromium (its headless shell) driven by Playwright (browser downloads do not work here)."""
    from playwright.sync_api import sync_playwright

    if not Path(CHROMIUM_PATH).exists():
        pytest.fail(f"{CHROMIUM_PATH} is missing: `make test` installs Debian's chromium-headless-shell package.")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM_PATH, args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def page(chromium, request: pytest.FixtureRequest):
    """A fresh browser tab; its console errors fail the test, and a failing test leaves a screenshot."""
    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    yield tab
    call = getattr(request.node, "call_report", None)
    if not tab.is_closed() and (call is None or call.failed):
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        tab.screenshot(path=str(ARTIFACTS_DIR / f"{request.node.name}.png"))
    context.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


@pytest.fixture
def demo_accounts(app) -> dict[str, str]:
    """The demo accounts `telelab up` creates, with their generated passwords."""
    from middleware.lab_runner import ensure_demo_accounts

    return {name: password for name, _role, password in ensure_demo_accounts(app)}


# `make test` runs the files in parallel processes (pytest-xdist, --dist loadfile): each file runs whole, in its
# order, in one process, and each process has its own session fixtures (lab-1, Chromium, the migrated templates).
# Files that share something of the machine's rather than of the process's run in one process, one after another:
# Ray's clusters (a Ray started without an address joins a cluster running on the machine, and a failed start stops
# every Ray of the machine), and labs of several web processes on PostgreSQL (each process's pool holds up to 15 of
# the server's 100 connections, and two such labs at once would also slow each other's measured steps). A group runs
# at its first file's place, before files that come earlier than its others, so its files leave lab-1 as they found it.
# The files of tests marked `alone` join the labs' group and run at its end, one after another (pytest_collection_
# modifyitems): the machine is emptied for them once, not once per test (each wait idled the suite's processes).
SAME_PROCESS_FILES = {
    "tests/integration/farm/test_ray_farm.py": "ray",
    "tests/integration/benchmarks/test_farm_benchmark_smoke.py": "ray",
    **dict.fromkeys([
        "tests/e2e/test_class_across_workers.py",
        "tests/e2e/test_lab_with_workers.py",
        "tests/integration/benchmarks/test_capacity_benchmark_smoke.py",
        "tests/integration/benchmarks/test_database_load_benchmark_smoke.py",
        "tests/integration/benchmarks/test_workers_benchmark_smoke.py",
        "tests/integration/middleware/test_rolling_restart.py",
        "tests/e2e/test_class_wall_across_workers.py",
        "tests/e2e/test_robot_pools.py",
        "tests/integration/access/test_vanished_seat_across_workers.py",
        "tests/integration/middleware/test_events_across_workers.py",
    ], "postgresql-labs"),
}


def _alone(item: pytest.Item) -> bool:
    return item.get_closest_marker("alone") is not None


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The modules holding tests marked `alone` last, each whole and in its order (every suite process sorts alike),
    those that also hold unmarked tests first among them (an unmarked test between two marked ones gives the machine
    back, and the next marked one waits for it again)."""
    alone_modules = {item.module for item in items if _alone(item)}  # type: ignore[attr-defined]
    mixed_modules = {item.module for item in items if not _alone(item)} & alone_modules  # type: ignore[attr-defined]

    def place(item: pytest.Item) -> int:
        module = getattr(item, "module", None)
        return 0 if module not in alone_modules else 1 if module in mixed_modules else 2

    items.sort(key=place)


SUITE_PROCESSES_MAX = 4  # each holds up to a PostgreSQL lab's 15 connections and its tests' own of the server's 100


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """`-n logical` (`make test`): one process more than the logical cores, at most SUITE_PROCESSES_MAX. A browser or
    robot test waits on a robot's or a page's real time much of its run, and a third process on 2 cores fills it."""
    return min(len(os.sched_getaffinity(0)) + 1, SUITE_PROCESSES_MAX)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """--dist loadfile, with the files of SAME_PROCESS_FILES put together."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LoadFileSharingMachineResources(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = super()._split_scope(nodeid)
            return SAME_PROCESS_FILES.get(path, path)

    return LoadFileSharingMachineResources(config, log)


# A test marked `alone` measures wall-clock bounds across processes ("another host takes the duty over within a
# second", a restart's chat lines answered in time): with several suite processes it starts only once every other
# process has ended its current test, and they start none until it ends, so its bounds are not the other tests' load.
# flock(2) on one file per run, shared by every other test and held alone by a marked one, behind a turnstile that
# the marked test holds while it waits (else the others' overlapping turns could hold the file shared forever). A
# marked test followed by another keeps the machine for it.
def _suite_lock_files() -> tuple[Path, Path] | None:
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:
        return None
    base = Path(tempfile.gettempdir()) / f"telelab-suite-{run}"
    return base.with_suffix(".turnstile"), base.with_suffix(".share")


class MachineShare:
    """One suite process's share of the machine: shared for an ordinary test, the whole of it for a marked one."""

    def __init__(self) -> None:
        self._share = None  # the lock file, open while a share is held (flock holds while it is open)
        self._alone = False

    def take(self, alone: bool) -> None:
        if self._share is not None and alone and self._alone:
            return  # kept since the marked test before
        self.give_back()
        files = _suite_lock_files()
        if files is None:
            return
        import fcntl

        with files[0].open("a") as turnstile:
            fcntl.flock(turnstile, fcntl.LOCK_EX)
            share = files[1].open("a")
            try:
                fcntl.flock(share, fcntl.LOCK_EX if alone else fcntl.LOCK_SH)
            except BaseException:
                share.close()
                raise
            finally:
                fcntl.flock(turnstile, fcntl.LOCK_UN)
        self._share, self._alone = share, alone

    def give_back(self) -> None:
        if self._share is not None:
            self._share.close()
            self._share, self._alone = None, False


@contextmanager
def share_of_the_machine(alone: bool) -> Iterator[None]:
    """The machine shared with the suite's other processes' tests, or, alone, to this test by itself."""
    share = MachineShare()
    share.take(alone)
    try:
        yield
    finally:
        share.give_back()


_machine = MachineShare()
_next_items: dict[str, pytest.Item | None] = {}


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    _next_items[item.nodeid] = nextitem
    try:
        return (yield)
    finally:
        _next_items.pop(item.nodeid, None)


@pytest.fixture(autouse=True)
def _share_of_the_machine(request: pytest.FixtureRequest) -> Iterator[None]:
    alone = _alone(request.node)
    _machine.take(alone)
    yield
    following = _next_items.get(request.node.nodeid)
    if not (alone and following is not None and _alone(following)):
        _machine.give_back()


# Figures a test wants read at the end of `make test` (record_property("summary", line)), from any xdist worker.
_summaries: list[str] = []


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """Keeps the test's own outcome on it, for fixtures that act on a failure only (the page's screenshot)."""
    report = yield
    if report.when == "call":
        item.call_report = report  # type: ignore[attr-defined]
    return report


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.when == "call":
        _summaries.extend(str(value) for name, value in report.user_properties if name == "summary")
    timeline = os.environ.get("TELELAB_TEST_TIMELINE")
    if timeline and hasattr(report, "node"):  # the controller, hearing a suite process's report: where time goes
        with open(timeline, "a", encoding="utf-8") as out:
            out.write(json.dumps({"process": report.node.gateway.id, "test": report.nodeid, "when": report.when,
                                  "outcome": report.outcome, "start": report.start, "stop": report.stop}) + "\n")


def pytest_terminal_summary(terminalreporter) -> None:
    for line in _summaries:
        terminalreporter.write_line(line)


EXIT_GRACE_S = 60
_exit_status = {"code": 0}


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _exit_status["code"] = int(exitstatus)
    _drop_migrated_templates()


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    """A thread left running by a test (a WebSocket reader, a server) must not keep the run from ending:
    CI would wait out its whole time limit and report nothing. After a grace, name the threads and exit
    with pytest's own status. A pytest-xdist worker is not watched: it lives on, idle, until the main process ends
    the run (which kills a worker that has not ended 10 s later)."""
    import faulthandler
    import sys

    if hasattr(config, "workerinput"):
        return

    def leave() -> None:
        threading.Event().wait(EXIT_GRACE_S)
        lingering = [t.name for t in threading.enumerate() if not t.daemon and t is not threading.main_thread()]
        print(f"\npytest finished but threads kept the process alive after {EXIT_GRACE_S} s: {lingering}",
              file=sys.stderr, flush=True)
        faulthandler.dump_traceback(file=sys.stderr, all_threads=True)
        os._exit(_exit_status["code"])

    threading.Thread(target=leave, name="exit-watchdog", daemon=True).start()
