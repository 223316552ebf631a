"""A class spread over three web hosts on one PostgreSQL database, behind Debian's nginx (issue 19).

Three gunicorn processes on three ports stand for three web hosts, started as the README's multi-host section starts
one (`gunicorn -k gthread ... 'middleware:create_app()'`, the same secret key and database on each); nginx runs the
README's site file (deploy/nginx/telelab.conf) with only its upstream's server lines replaced by the three. One lab
robot, a real skill server on the course-B track, runs in this process so that the trial can place it on the track.
Then a host's worker is killed with SIGKILL mid-trial, and the host holding the access ticker's election is killed
(its duty observed: a turn of TURN_S, the default turn of students in no course, must end on time).

Which host serves whom is made deterministic by talking to a host directly where it matters: student1's requests
and sockets go to host 1, student2's Chromium opens its pages on host 2, the tutor acts on host 3; the admin and a
second follower socket of student1 go through nginx (whichever host it picks). Each database connection names its
host (PGAPPNAME), so pg_stat_activity says which host holds the access ticker's advisory lock.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.request import Request, urlopen

import psycopg
import pytest
import simple_websocket

from benchmarks.lab_under_test import WebSocketClient
from benchmarks.ports import free_port
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LabClient, postgres_database, ready_for_trials
from tests.e2e.test_experiment import place
from tests.e2e.test_lab_with_workers import NGINX, _answers, _children, _command, _listens
from tests.e2e.test_panels import wait_for
from tests.integration.lab.test_robot_channels import closed_with

pytestmark = [pytest.mark.e2e, pytest.mark.postgres, pytest.mark.alone]

REPO = Path(__file__).resolve().parents[2]
HOSTS = 3
TURN_S = 3  # the turn of a student in no course (TELELAB_DEFAULT_TURN_S; a course's turn is 10 s at least)
CHAT_WITHIN_S = 0.2  # the figure, for the median: one message on a shared, loaded 2-core machine may lag
AT_ONCE_S = 1.0
ACCOUNTS = {"student1": "student", "student2": "student", "tutor1": "tutor", "admin1": "admin",
            "trialist": "student", "holder": "student", "waiter": "student"}
TRACK_A = (-3.0, -1.5)  # skill_server/sim/scenes.py, track_b_scene: A, then B at the end of the corridor
TRACK_B = (3.0, 1.5)


@dataclass
class WebHost:
    """One web host: a gunicorn master with one threaded worker on its own port."""

    name: str
    url: str
    master: subprocess.Popen[bytes]
    log: Path

    def worker_pid(self) -> int | None:
        """The worker serving now (a fork of the master: the same command line)."""
        command = _command(self.master.pid)
        workers = [pid for pid in _children(self.master.pid) if _command(pid) == command]
        return workers[0] if len(workers) == 1 else None

    def kill_worker(self) -> int:
        """SIGKILL to the worker, as when a host's process dies; gunicorn's master then starts another."""
        pid = self.worker_pid()
        assert pid is not None, f"{self.name} has no single worker"
        os.kill(pid, signal.SIGKILL)
        return pid

    def wait_serving(self, not_pid: int | None = None) -> None:
        """Waits until a worker (other than not_pid) answers."""
        try:
            wait_for(lambda: self.worker_pid() not in (None, not_pid) and _answers(f"{self.url}/healthz"), 60,
                     f"{self.name} never served")
        except AssertionError as failure:
            raise AssertionError(f"{failure}; its log ends:\n{self.log.read_text()[-3000:]}") from None


@dataclass
class Cluster:
    """The running lab: its database, its robot (in this process), the web hosts, nginx, the accounts' ids."""

    database_url: str
    robot: Any  # skill_server.server.SkillServer
    hosts: list[WebHost]
    nginx: str
    ids: dict[str, int]
    tour_id: int

    @property
    def urls(self) -> list[str]:
        """The hosts' own addresses, host 1 first."""
        return [host.url for host in self.hosts]

    def host_named(self, name: str) -> WebHost:
        """The host whose database connections carry name."""
        return next(host for host in self.hosts if host.name == name)


def _prepare(database_url: str) -> tuple[dict[str, int], int]:
    """The accounts, a course (tutor1 teaching student1 and student2) and a tour, straight into the database."""
    from sqlalchemy.orm import Session

    from middleware.auth.services import create_user
    from middleware.db import make_engine, upgrade_to_head
    from middleware.models import Course, CourseMembership
    from middleware.teaching.demo_content import DEMO_TOURS
    from middleware.teaching.tours import save_tour

    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    try:
        with Session(engine) as session:
            ids = {name: create_user(session, name, role, STUDENT_PASSWORD).id for name, role in ACCOUNTS.items()}
            course = Course(code="SCALE", title="Scaling out")
            session.add(course)
            session.flush()
            session.add_all(CourseMembership(course_id=course.id, user_id=ids[name], role=role)
                            for name, role in (("tutor1", "tutor"), ("student1", "student"), ("student2", "student")))
            tour_id = save_tour(session, DEMO_TOURS[1], None, None).id
            ready_for_trials(session, "trialist")
            session.commit()
            return ids | {"course": course.id}, tour_id
    finally:
        engine.dispose()


def _start_host(index: int, database_url: str, robot_address: str, logs: Path) -> WebHost:
    port = free_port()
    environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": "three-hosts-one-key",
                   "TELELAB_ROBOTS": f"lab-1={robot_address}", "TELELAB_TRUSTED_PROXIES": "1",
                   "TELELAB_DEFAULT_TURN_S": str(TURN_S), "PGAPPNAME": f"web-{index}", "PYTHONUNBUFFERED": "1"}
    log_path = logs / f"web-{index}.log"
    with log_path.open("wb") as log:
        master = subprocess.Popen(
            [sys.executable, "-m", "gunicorn", "-k", "gthread", "--threads", "50", "-w", "1", "-b", f"127.0.0.1:{port}",
             "--graceful-timeout", "5", "--log-level", "warning", "middleware:create_app()"],
            cwd=REPO, env=environment, stdout=log, stderr=subprocess.STDOUT)
    return WebHost(f"web-{index}", f"http://127.0.0.1:{port}", master, log_path)


@contextlib.contextmanager
def _nginx(upstreams: list[str], prefix: Path, tls: tuple[Path, Path] | None = None) -> Iterator[str]:
    """Debian's nginx with the README's site file, its upstream's server lines replaced by the hosts; with tls
    (certificate, key for localhost) over HTTPS, as the README's HTTPS set-up adds (test_lti_cross_site.py)."""
    if not os.path.exists(NGINX):
        pytest.fail(f"{NGINX} is missing: `make test` installs Debian's nginx package.")
    port = free_port()
    site = (REPO / "deploy" / "nginx" / "telelab.conf").read_text()
    servers = "".join(f"    server {address.removeprefix('http://')};\n" for address in upstreams)
    site, replaced = re.subn(r"^ *server 127\.0\.0\.1:5000;.*\n", servers, site, flags=re.MULTILINE)
    assert replaced == 1, "the README's nginx site no longer has the one upstream server line this test replaces"
    listen = f"listen 127.0.0.1:{port};" if tls is None else \
        f"listen 127.0.0.1:{port} ssl;\n    ssl_certificate {tls[0]};\n    ssl_certificate_key {tls[1]};"
    site = site.replace("listen 8080;", listen)
    (prefix / "telelab.conf").write_text(site)
    (prefix / "nginx.conf").write_text(
        ("user root;\n" if os.geteuid() == 0 else "")
        + f"pid {prefix}/nginx.pid;\nerror_log {prefix}/error.log;\nevents {{}}\n"
        + f"http {{\n  access_log off;\n  client_body_temp_path {prefix}/body;\n  proxy_temp_path {prefix}/proxy;\n"
        + f"  include {prefix}/telelab.conf;\n}}\n")
    server = subprocess.Popen([NGINX, "-p", str(prefix), "-c", str(prefix / "nginx.conf"), "-g", "daemon off;"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}" if tls is None else f"https://localhost:{port}"
    ready = (lambda: _answers(f"{url}/healthz")) if tls is None else (lambda: _listens(f"127.0.0.1:{port}"))
    try:
        wait_for(lambda: server.poll() is not None or ready(), 20, "nginx never answered")
        assert server.poll() is None, f"nginx did not start: {(prefix / 'error.log').read_text()}"
        yield url
    finally:
        server.terminate()
        server.wait(10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cluster]:
    """Three web hosts, nginx in front of them, one course-B robot, on a fresh PostgreSQL database."""
    from skill_server.server import create_server

    logs = tmp_path_factory.mktemp("hosts")
    with postgres_database() as database_url:
        ids, tour_id = _prepare(database_url)
        robot = create_server(port=0, scene="course-B", realtime=True, robot_name="lab-1")
        hosts: list[WebHost] = []
        try:
            hosts = [_start_host(index, database_url, f"127.0.0.1:{robot.port}", logs) for index in range(1, HOSTS + 1)]
            for host in hosts:
                host.wait_serving()
            with _nginx([host.url for host in hosts], tmp_path_factory.mktemp("nginx")) as nginx:
                yield Cluster(database_url, robot, hosts, nginx, ids, tour_id)
        finally:
            for host in hosts:
                host.master.terminate()
            for host in hosts:
                host.master.wait(30)
            robot.stop(grace_s=0.5)


class Person:
    """One login, used on whichever host a call names (one database and one secret key: a login holds on all)."""

    def __init__(self, cookie: str, csrf: str = "") -> None:
        self.cookie, self.csrf = cookie, csrf
        self._sockets: list[tuple[simple_websocket.Client, str]] = []

    @classmethod
    def log_in(cls, url: str, username: str) -> Person:
        """username logged in through the form on the host at url."""
        client = LabClient(url)
        assert client.login(username, STUDENT_PASSWORD) == 302, f"{username} could not log in on {url}"
        csrf = client.csrf_token("/lab")  # after this the cookie also holds the CSRF secret
        return cls(client.cookie_header(), csrf)

    @classmethod
    def of_browser(cls, context) -> Person:
        """The login of a browser context (its cookies; the page already carries the CSRF secret)."""
        return cls("; ".join(f"{cookie['name']}={cookie['value']}" for cookie in context.cookies()))

    def call(self, url: str, method: str, path: str, body: object = None) -> tuple[int, dict]:
        """A JSON request as the pages make it; (status, decoded body)."""
        headers = {"Cookie": self.cookie, "Accept": "application/json", "X-CSRFToken": self.csrf}
        data = None
        if body is not None:
            data, headers["Content-Type"] = json.dumps(body).encode(), "application/json"
        try:
            with urlopen(Request(url + path, data=data, method=method, headers=headers), timeout=10) as response:
                return response.status, json.loads(response.read() or b"{}")
        except Exception as error:  # urllib raises for 4xx and 5xx: they are answers here
            if hasattr(error, "code"):
                with error:  # type: ignore[attr-defined]
                    return error.code, json.loads(error.read() or b"{}")  # type: ignore[attr-defined]
            raise

    def socket(self, url: str, path: str) -> simple_websocket.Client:
        """A WebSocket to path on the host at url, carrying this login."""
        opened = WebSocketClient.connect(url.replace("http", "ws", 1) + path, headers={"Cookie": self.cookie})
        self._sockets.append((opened, path))
        return opened

    def close(self) -> None:
        """Leaves the queues this login joined (a closed socket's seat waits for its reconnection) and closes the
        sockets it opened."""
        for opened, path in self._sockets:
            with contextlib.suppress(Exception):  # closed by the server already
                if path.endswith("/queue"):
                    opened.send(json.dumps({"type": "leave"}))
                opened.close()
        self._sockets.clear()


@pytest.fixture
def people() -> Iterator[Callable[[str, str], Person]]:
    """Logs users in (on the host given); their sockets are closed when the test ends, passed or failed."""
    made: list[Person] = []

    def log_in(url: str, username: str) -> Person:
        made.append(Person.log_in(url, username))
        return made[-1]

    yield log_in
    for person in made:
        person.close()


def message_until(ws, kind: str, wanted: Callable[[dict], bool] = lambda _message: True,
                  timeout_s: float = 5.0) -> dict:
    """The first text message of type kind that wanted accepts (binary and other messages are skipped)."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        raw = ws.receive(timeout=left)
        if isinstance(raw, str):
            message = json.loads(raw)
            if message.get("type") == kind and wanted(message):
                return message
    raise AssertionError(f"no {kind} message as wanted within {timeout_s} s")


def first_frame(ws, timeout_s: float = 10.0) -> bytes:
    """The first camera frame (binary) on ws: the robot is rendering for it."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        raw = ws.receive(timeout=left)
        if isinstance(raw, bytes):
            return raw
    raise AssertionError(f"no camera frame within {timeout_s} s")


# The moment (Date.now(), the same clock as time.time()) an element first matches, noted by a MutationObserver in
# the page, so the time is what the page shows and not when the test next looked.
WATCH = """([key, selector, text]) => {
    window.seenAt = window.seenAt || {};
    delete window.seenAt[key];
    const matches = () => [...document.querySelectorAll(selector)]
        .some((element) => text === null || (element.textContent || "").includes(text));
    const look = () => {
        if (key in window.seenAt) return true;
        if (!matches()) return false;
        window.seenAt[key] = Date.now();
        return true;
    };
    if (look()) return;
    const observer = new MutationObserver(() => { if (look()) observer.disconnect(); });
    observer.observe(document.documentElement,
                     { subtree: true, childList: true, attributes: true, characterData: true });
}"""


def watch(tab, key: str, selector: str, text: str | None = None) -> None:
    """Starts noting when selector (holding text) first shows in tab."""
    tab.evaluate(WATCH, [key, selector, text])


def seen_at(tab, key: str, timeout_s: float = 10.0) -> float:
    """The wall-clock time [s] at which tab first showed what watch(key) waits for."""
    tab.wait_for_function("key => window.seenAt && key in window.seenAt", arg=key, timeout=timeout_s * 1000)
    return tab.evaluate("key => window.seenAt[key]", key) / 1000.0


def _log_in_page(tab, url: str, username: str) -> None:
    tab.goto(f"{url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def _ms(seconds: list[float]) -> str:
    return ", ".join(f"{s * 1000:.0f} ms" for s in seconds)


def test_two_students_on_different_hosts_share_the_turn_chat_a_live_tour_and_delays_and_a_disabled_account_is_refused(
        page, cluster: Cluster, people) -> None:
    host1, host2, host3 = cluster.urls
    student1 = people(host1, "student1")
    queue1 = student1.socket(host1, "/ws/robots/lab-1/queue")
    assert message_until(queue1, "queue", lambda seat: seat["is_controller"])  # first in line: control at once
    chat1 = student1.socket(host1, "/ws/robots/lab-1/chat")
    message_until(chat1, "history")

    _log_in_page(page, host2, "student2")
    page.goto(f"{host2}/lab/lab-1")
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
    page.locator('queue-panel[data-role="waiting"]').wait_for(timeout=10_000)
    assert "student1 is driving" in (page.locator('[data-field="queue-summary"]').text_content() or "")

    # The turn: student1 passes it on host 1, student2's console on host 2 shows control; and back, by the button.
    watch(page, "control", 'queue-panel[data-role="controller"]')
    passed_at = time.time()
    queue1.send(json.dumps({"type": "pass"}))
    to_student2 = seen_at(page, "control") - passed_at
    clicked_at = time.time()
    page.get_by_role("button", name="Pass the turn").click()
    message_until(queue1, "queue", lambda seat: seat["is_controller"], timeout_s=5.0)
    to_student1 = time.time() - clicked_at
    page.locator('queue-panel[data-role="waiting"]').wait_for(timeout=5000)
    print(f"\nturn passed across hosts: to student2's console {_ms([to_student2])}, back {_ms([to_student1])}")
    assert to_student2 < AT_ONCE_S and to_student1 < AT_ONCE_S, "a passed turn shows on the other host at once"

    # Chat, both ways: student1 posts on host 1 and student2's console shows it; student2 types, host 1's socket hears.
    page.get_by_role("tab", name="Chat").click()
    page.locator("#chat-input:enabled").wait_for(timeout=10_000)
    to_page, to_socket = [], []
    for round_ in (1, 2, 3):
        body = f"from host 1, round {round_}"
        watch(page, body, 'chat-panel [data-field="chat-body"]', body)
        posted_at = time.time()
        status, answer = student1.call(host1, "POST", "/api/robots/lab-1/chat", {"body": body})
        assert status == 201, answer
        to_page.append(seen_at(page, body) - posted_at)
        typed = f"from host 2, round {round_}"
        page.get_by_label("Message to everyone on this robot").fill(typed)
        sent_at = time.time()
        page.keyboard.press("Enter")
        message_until(chat1, "message", lambda message, typed=typed: message["message"]["body"] == typed)
        to_socket.append(time.time() - sent_at)
    print(f"chat across hosts: host 1 -> student2's page {_ms(to_page)}; student2's page -> host 1 {_ms(to_socket)}")
    assert statistics.median(to_page + to_socket) < CHAT_WITHIN_S, "chat reaches the other host within 200 ms"
    assert max(to_page + to_socket) < AT_ONCE_S, "every message is pushed at once, none waits for a poll"
    page.get_by_role("tab", name="Drive").click()

    # A live tour led on host 3: every follower (host 1, nginx's pick, student2's tab on host 2) gets each step.
    tutor = people(host3, "tutor1")
    status, live = tutor.call(host3, "POST", f"/api/tours/{cluster.tour_id}/sessions",
                              {"robot": "lab-1", "course_id": cluster.ids["course"]})
    assert status == 201, live
    follower1 = student1.socket(host1, f"/ws/tour-sessions/{live['id']}")
    follower_via_nginx = student1.socket(cluster.nginx, f"/ws/tour-sessions/{live['id']}")
    for follower in (follower1, follower_via_nginx):
        message_until(follower, "state", lambda state: state["step_index"] == 0)
    tour_tab = page.context.new_page()
    try:
        tour_tab.goto(f"{host2}/tours/sessions/{live['id']}")
        tour_tab.wait_for_selector("#live[data-step='0']")
        watch(tour_tab, "step", "#live[data-step='1']")
        stepped_at = time.time()
        status, answer = tutor.call(host3, "POST", f"/api/tour-sessions/{live['id']}", {"action": "step", "index": 1})
        assert status == 200, answer
        delays, steps = [], []
        for follower in (follower1, follower_via_nginx):
            steps.append(message_until(follower, "state", lambda state: state["step_index"] == 1)["step"])
            delays.append(time.time() - stepped_at)
        delays.append(seen_at(tour_tab, "step") - stepped_at)
        print(f"tour step on host 3 -> followers (host 1, via nginx, student2's tab on host 2): {_ms(delays)}")
        assert max(delays) < AT_ONCE_S, "a tour step reaches every follower at once"
        assert steps[0] == steps[1] and steps[0]["title"] != live["step"]["title"]
        assert tour_tab.locator("[data-field=step-title]").text_content() == steps[0]["title"]
        status, _ = tutor.call(host3, "POST", f"/api/tour-sessions/{live['id']}", {"action": "end"})
        assert status == 200
        tour_tab.locator("[data-field=control]", has_text="The class has ended.").wait_for(timeout=5000)
    finally:
        tour_tab.close()

    # A delay set on host 3 applies at once on host 1 (the video is held by it) and shows on student2's console.
    telemetry1 = student1.socket(host1, "/ws/robots/lab-1/telemetry")
    message_until(telemetry1, "telemetry")
    set_at = time.time()
    status, _ = tutor.call(host3, "PUT", "/api/experiment/delays/student1", {"delay_s": 1.0})
    assert status == 200
    message_until(telemetry1, "status", lambda status: status.get("injected_delay_s") == 1.0, timeout_s=3.0)
    applied_at = time.time()
    applied_in = applied_at - set_at
    # What the robot captured from then on is held for the new delay (one message sent before may overtake it).
    ages = [time.time() - message["capture_unix_s"] for message in (
        message_until(telemetry1, "telemetry", lambda message: message["capture_unix_s"] > applied_at)
        for _ in range(3))]
    assert min(ages) > 0.9, f"the video after the change is not held by the new delay: ages {ages}"
    watch(page, "delay", '[data-field="injected-delay"]:not([hidden])', "Added delay 1.0 s")
    set_at_2 = time.time()
    status, _ = tutor.call(host3, "PUT", "/api/experiment/delays/student2", {"delay_s": 1.0})
    assert status == 200
    shown_in = seen_at(page, "delay") - set_at_2
    print(f"delay set on host 3 -> applied by host 1 {_ms([applied_in])}, shown on host 2's console {_ms([shown_in])}")
    assert applied_in < AT_ONCE_S and shown_in < AT_ONCE_S, "a delay change applies at once on the other hosts"
    for username in ("student1", "student2"):
        assert tutor.call(host3, "PUT", f"/api/experiment/delays/{username}", {"delay_s": 0})[0] == 200
    queue1.send(json.dumps({"type": "leave"}))  # student2 has the robot, then leaves it free for the next test
    page.locator('queue-panel[data-role="controller"]').wait_for(timeout=5000)
    page.get_by_role("button", name="Leave the queue").click()
    page.locator('queue-panel[data-role="watching"]').wait_for(timeout=5000)

    # An admin disables student2 through nginx: every host refuses the login at once and closes its sockets.
    from middleware.realtime import CLOSE_NOT_LOGGED_IN

    student2 = Person.of_browser(page.context)
    elsewhere = [student2.socket(host1, "/ws/link"), student2.socket(host3, "/ws/robots/lab-1/chat")]
    message_until(elsewhere[1], "history")
    admin = people(cluster.nginx, "admin1")
    everywhere = (*cluster.urls, cluster.nginx)
    for url in everywhere:  # each host checks this login just before: a verdict it keeps must not outlive the change
        assert student2.call(url, "GET", "/api/experiment/state")[0] == 200
    watch(page, "ended", "#session-ended:not([hidden])")
    disabled_at = time.time()  # from the admin's click: a host may hear of it before the admin's answer arrives
    status, answer = admin.call(cluster.nginx, "PATCH", f"/api/users/{cluster.ids['student2']}", {"is_active": False})
    assert status == 200 and answer["user"]["is_active"] is False, answer
    next_answers, last_answers, refused_after = {}, {}, {}
    for url in everywhere:  # the next request, then again until refused (an announcement takes a few ms)
        next_answers[url] = status = student2.call(url, "GET", "/api/experiment/state")[0]
        while status == 200 and time.time() - disabled_at < 2.0:
            status = student2.call(url, "GET", "/api/experiment/state")[0]
        last_answers[url], refused_after[url] = status, time.time() - disabled_at
    closed = [closed_with(ws, 2.0) for ws in elsewhere]
    closed_in = time.time() - disabled_at
    page_in = seen_at(page, "ended", timeout_s=2.0) - disabled_at
    print(f"account disabled through nginx -> hosts 1, 2, 3 and nginx answered its next request "
          f"{list(next_answers.values())} and refused it after {_ms(list(refused_after.values()))}; "
          f"sockets on hosts 1 and 3 closed within {_ms([closed_in])}, student2's console on host 2 says so after "
          f"{_ms([page_in])}")
    assert set(last_answers.values()) == {401}, f"a host kept serving the disabled account: {last_answers}"
    assert max(refused_after.values()) < 0.5, f"a host served the disabled account for a while: {refused_after}"
    assert closed == [CLOSE_NOT_LOGGED_IN] * 2 and closed_in < 2.0 and page_in < 2.0, closed
    time.sleep(max(0.0, disabled_at + 1.2 - time.time()))  # past the hosts' verdict lifetime (RECHECK_S)
    assert {url: student2.call(url, "GET", "/api/experiment/state")[0] for url in everywhere} == dict.fromkeys(
        everywhere, 401), "no host lets the disabled account back in later"
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "three-hosts-disabled-console.png"))
    student2.close()


def test_a_host_killed_mid_trial_leaves_the_trial_to_end_correctly_on_another(cluster: Cluster, people) -> None:
    host1, host2, _ = cluster.urls
    trialist = people(host1, "trialist")
    queue = trialist.socket(host1, "/ws/robots/lab-1/queue")
    message_until(queue, "queue", lambda seat: seat["is_controller"], timeout_s=10)
    place(cluster.robot, *TRACK_A)
    status, answer = trialist.call(host1, "POST", "/api/experiment/trials", {"robot_name": "lab-1"})
    assert status == 201, answer
    trial = answer["trial"]
    telemetry = trialist.socket(host1, "/ws/robots/lab-1/telemetry")
    message_until(telemetry, "status", lambda status: status.get("injected_delay_s") == trial["delay_s"])
    # The console's camera, as during a real trial (a placement wakes a parked robot, so the track monitor sees it).
    camera = trialist.socket(host1, "/ws/robots/lab-1/camera")
    first_frame(camera)

    departed_from = sim_now(cluster)
    place(cluster.robot, TRACK_A[0] + 0.6, TRACK_A[1])  # off A: the run starts
    place(cluster.robot, -2.0, -1.0)  # onto the corridor's white line: an error, and the robot is back at A
    place(cluster.robot, TRACK_A[0] + 0.6, TRACK_A[1])
    run = trialist.call(host1, "GET", "/api/experiment/state")[1]["run"]
    assert (run["phase"], run["errors"], run["finished"]) == ("to_b", 1, False), run

    killed_from = sim_now(cluster)
    killed = cluster.host_named("web-1").kill_worker()  # the host that started the trial and serves its sockets
    for ws in (queue, telemetry, camera):
        with contextlib.suppress(simple_websocket.ConnectionClosed):
            closed_with(ws, 5.0)
    camera = trialist.socket(host2, "/ws/robots/lab-1/camera")  # the page reconnects, here to another host
    first_frame(camera)
    queue = trialist.socket(host2, "/ws/robots/lab-1/queue")
    assert message_until(queue, "queue")["is_controller"], "the seat and control waited for the reconnection"
    telemetry = trialist.socket(host2, "/ws/robots/lab-1/telemetry")
    message_until(telemetry, "status", lambda status: status.get("injected_delay_s") == trial["delay_s"])
    state = trialist.call(host2, "GET", "/api/experiment/state")[1]
    assert state["trial"]["id"] == trial["id"] and state["trial"]["status"] == "assigned", state
    assert (state["run"]["phase"], state["run"]["errors"]) == ("to_b", 1), state["run"]

    place(cluster.robot, 0.0, 0.0)
    arrived_from = sim_now(cluster)
    place(cluster.robot, *TRACK_B)
    arrived_by = sim_now(cluster)
    status, answer = trialist.call(host2, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 200, answer
    recorded = answer["trial"]
    assert recorded["status"] == "completed" and recorded["errors"] == 1, recorded
    assert (recorded["course"], recorded["delay_s"], recorded["feedback"]) == (
        trial["course"], trial["delay_s"], trial["feedback"])
    # The track is timed in the robot's sim time (which falls behind the wall clock on a busy machine), to 1 ms.
    assert arrived_from - killed_from - 1e-3 <= recorded["total_time_s"] <= arrived_by - departed_from + 1e-3, \
        "the run is timed from the departure, across the host that died"
    message_until(telemetry, "status", lambda status: status.get("injected_delay_s") == 0.0,
                  timeout_s=trial["delay_s"] + 3.0)  # the trial's delay ended with it, on the host that finished it
    state = trialist.call(host2, "GET", "/api/experiment/state")[1]
    assert state["trial"] is None and state["last_trial"]["id"] == trial["id"]
    status, answer = trialist.call(host2, "POST", f"/api/experiment/trials/{trial['id']}/finish", {})
    assert status == 409, "a trial is recorded once"
    queue.send(json.dumps({"type": "leave"}))
    cluster.host_named("web-1").wait_serving(not_pid=killed)


def sim_now(cluster: Cluster) -> float:
    """The lab robot's sim time now (its world runs in the test's process)."""
    return cluster.robot.world.snapshot.sim_time_s


def _ticker_holder(connection: psycopg.Connection) -> str | None:
    """The host whose worker holds the access ticker's advisory lock (each host names its connections)."""
    from middleware.access.coordinator import ACCESS_TICKER_LOCK

    row = connection.execute(
        "SELECT a.application_name FROM pg_locks l JOIN pg_stat_activity a ON a.pid = l.pid "
        "WHERE l.locktype = 'advisory' AND l.granted AND l.classid = 0 AND l.objid::bigint = %s AND l.objsubid = 1",
        (ACCESS_TICKER_LOCK,)).fetchone()
    return row[0] if row else None


def test_when_the_host_running_the_access_ticker_is_killed_another_takes_its_duties_over_within_a_second(
        cluster: Cluster, people) -> None:
    holder = people(cluster.urls[0], "holder")
    # A queue socket on every host: each host's ticker runs (and asks for the lock every tick); holder has control.
    for host in cluster.hosts:
        message_until(holder.socket(host.url, "/ws/robots/lab-1/queue"), "queue", lambda seat: seat["is_controller"],
                      timeout_s=10)
    dsn = cluster.database_url.replace("postgresql+psycopg://", "postgresql://", 1)
    with psycopg.connect(dsn, autocommit=True) as connection:
        wait_for(lambda: _ticker_holder(connection) is not None, 5, "no host holds the access ticker")
        running = _ticker_holder(connection)
        survivor = next(host for host in cluster.hosts if host.name != running)
        waiter = people(survivor.url, "waiter")
        joined_from = time.monotonic()
        waiting = waiter.socket(survivor.url, "/ws/robots/lab-1/queue")
        seat = message_until(waiting, "queue", lambda seat: seat["in_queue"])
        joined_by = time.monotonic()  # holder's turn (TURN_S) counts from here: someone waits
        assert not seat["is_controller"] and seat["controller"] == "holder", seat

        killed = cluster.host_named(running).kill_worker()
        killed_at = time.monotonic()
        while (now_running := _ticker_holder(connection)) in (None, running):
            assert time.monotonic() - killed_at < 5.0, "nobody took the access ticker over"
            time.sleep(0.02)
        taken_over_in = time.monotonic() - killed_at
    # The duty: nothing but the ticker ends a turn whose time is up, so the waiter gets the robot only if the new
    # runner ticks.
    message_until(waiting, "queue", lambda seat: seat["is_controller"], timeout_s=TURN_S + 5.0)
    moved_at = time.monotonic()
    print(f"\naccess ticker: {running} killed -> {now_running} holds the lock after {_ms([taken_over_in])}; "
          f"the {TURN_S} s turn passed {_ms([moved_at - joined_from])} after the waiter's socket opened")
    assert taken_over_in < 1.0, "another host takes the ticker over within a second"
    assert killed_at + taken_over_in < joined_by + TURN_S, "the turn ended after the takeover: the new runner's duty"
    assert joined_from + TURN_S - 0.25 < moved_at < joined_by + TURN_S + 1.0, "the turn ends on time, not before"
    waiting.send(json.dumps({"type": "leave"}))
    cluster.host_named(running).wait_serving(not_pid=killed)
