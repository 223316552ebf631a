"""A rolling restart (SIGHUP to the gunicorn master, deploy/gunicorn.conf.py as deployments run it) under load: three
workers on PostgreSQL, twelve students chatting on sockets of their own, HTTP requests all along.

Each old worker leaves only once a new one serves in its place; a leaving worker answers the chat lines it has read,
then closes its sockets with 1012 (never 1006), and the students reconnect and chat on. A line sent as the socket
closed was never read, so never answered nor stored: the student sends it again (the chat panel's "Send again") and it
is stored once. The workers' hooks note when
each served and when each was told to leave (a test configuration wrapping the deployed one).
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from urllib.request import urlopen

import pytest
import simple_websocket
from sqlalchemy import select
from sqlalchemy.orm import Session

from benchmarks.ports import free_port
from tests.conftest import LabClient, add_test_account, migrate_to_head, postgres_database
from tests.e2e.test_lab_with_workers import _answers, _children
from tests.e2e.test_panels import wait_for

pytestmark = pytest.mark.alone

REPO = Path(__file__).resolve().parents[3]
WORKERS = 3
STUDENTS = 12
CHAT_PAUSE_S = (2.0, 2.6)  # a person's pace, under the chat's limit of 5 lines per 10 s

NOTED_CONFIG = '''
import os, signal, time
exec(compile(open({deployed!r}).read(), {deployed!r}, "exec"))
_settle = post_worker_init

def _note(event):
    with open(os.environ["ROLL_EVENTS"], "a") as log:
        log.write(f"{{time.monotonic()}} {{event}} {{os.getpid()}}\\n")

def post_worker_init(worker):
    _settle(worker)
    _note("serves")
    leave = signal.getsignal(signal.SIGTERM)

    def noted(signum, frame):
        _note("leaves")
        leave(signum, frame)

    signal.signal(signal.SIGTERM, noted)
'''


@dataclass
class Chatter:
    """One student's chat socket, written as a person writes: a line, its answer, a pause."""

    client: LabClient
    name: str
    closes: list[int] = field(default_factory=list)
    written: list[str] = field(default_factory=list)
    answered: dict[str, int] = field(default_factory=dict)
    unanswered: list[str] = field(default_factory=list)
    cut_off: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def run(self, stop: threading.Event) -> None:
        count, again = 0, None
        while not stop.is_set():
            try:
                ws = self.client.websocket("/ws/robots/lab-1/chat")
                assert json.loads(ws.receive(timeout=20))["type"] == "history"
            except Exception as error:  # noqa: BLE001 - a refused reconnection is the finding
                self.errors.append(f"connect: {error!r}")
                time.sleep(0.5)
                continue
            try:
                while not stop.is_set():
                    if again is None:
                        count += 1
                    line, again = again or f"{self.name} line {count}", None
                    ws.send(json.dumps({"type": "say", "body": line, "line": f"k-{count}"}))
                    self.written.append(line)
                    self._await_answer(ws, line)
                    stop.wait(random.uniform(*CHAT_PAUSE_S))
            except simple_websocket.ConnectionClosed as closed:
                self.closes.append(closed.reason)
                if self.written and self.written[-1] not in self.answered:
                    # Sent as the worker closed, never read, so never answered: the chat panel shows it unsent with
                    # "Send again", which the person clicks once the page has reconnected.
                    again = self.written[-1]
                    self.cut_off.append(again)
        ws.close()

    def _await_answer(self, ws, line: str) -> None:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            raw = ws.receive(timeout=max(0.1, deadline - time.monotonic()))
            if raw is None:
                continue
            message = json.loads(raw)
            if message["type"] == "sent":
                self.answered[line] = message["id"]
                return
            if message["type"] == "error":
                self.errors.append(f"{line}: {message}")
                return
        self.unanswered.append(line)


@pytest.fixture
def web(tmp_path, skill_server_address: str) -> Iterator[dict]:
    with postgres_database() as database_url:
        migrate_to_head(database_url)
        from middleware.db import make_engine

        engine = make_engine(database_url)
        with Session(engine) as session:
            for n in range(STUDENTS):
                add_test_account(session, f"chatter{n}", "student")
            session.commit()
        config = tmp_path / "gunicorn.noted.py"
        config.write_text(NOTED_CONFIG.format(deployed=str(REPO / "deploy" / "gunicorn.conf.py")))
        events = tmp_path / "events.log"
        port = free_port()
        environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": "rolling-restart",
                       "TELELAB_ROBOTS": f"lab-1={skill_server_address}", "ROLL_EVENTS": str(events),
                       "PYTHONUNBUFFERED": "1"}
        with (tmp_path / "gunicorn.log").open("wb") as log:
            master = subprocess.Popen(
                [sys.executable, "-m", "gunicorn", "-c", str(config), "-w", str(WORKERS), "-b", f"127.0.0.1:{port}",
                 "middleware:create_app()"], cwd=REPO, env=environment, stdout=log, stderr=subprocess.STDOUT)
        url = f"http://127.0.0.1:{port}"
        try:
            wait_for(lambda: master.poll() is not None or _noted(events, "serves") >= WORKERS, 120,
                     "the workers never served")
            assert master.poll() is None, (tmp_path / "gunicorn.log").read_text()
            wait_for(lambda: _answers(f"{url}/healthz"), 30, "the server never answered")
            yield {"url": url, "master": master, "events": events, "engine": engine,
                   "log": tmp_path / "gunicorn.log"}
        finally:
            master.send_signal(signal.SIGTERM)
            try:
                master.wait(30)
            except subprocess.TimeoutExpired:
                master.kill()
            engine.dispose()


def _events(path: Path) -> list[tuple[float, str, int]]:
    if not path.exists():
        return []
    return [(float(t), event, int(pid)) for t, event, pid in (line.split() for line in path.read_text().splitlines())]


def _noted(path: Path, kind: str) -> int:
    return sum(1 for _, event, _pid in _events(path) if event == kind)


def _probe_http(url: str, stop: threading.Event, failures: list[str], answered: list[int]) -> None:
    while not stop.is_set():
        try:
            with urlopen(f"{url}/healthz", timeout=20) as response:
                answered.append(response.status)
        except Exception as error:  # noqa: BLE001 - an unanswered request is the finding
            failures.append(repr(error))
        stop.wait(0.05)


def test_a_rolling_restart_under_load_keeps_a_worker_serving_and_answers_every_chat_line_it_read(web) -> None:
    from middleware.models import ChatMessage

    chatters = []
    for n in range(STUDENTS):
        client = LabClient(web["url"])
        assert client.login(f"chatter{n}") == 302
        chatters.append(Chatter(client, f"chatter{n}"))
    old_workers = set(_children(web["master"].pid))
    assert len(old_workers) == WORKERS

    stop, http_failures, http_answers = threading.Event(), [], []
    threads = [threading.Thread(target=c.run, args=(stop,)) for c in chatters]
    threads += [threading.Thread(target=_probe_http, args=(web["url"], stop, http_failures, http_answers))
                for _ in range(2)]
    for thread in threads:
        thread.start()
    try:
        wait_for(lambda: all(c.answered for c in chatters), 60, "not every student chatted before the restart")
        web["master"].send_signal(signal.SIGHUP)
        wait_for(lambda: not old_workers & set(_children(web["master"].pid)), 120, "the old workers never left")
        wait_for(lambda: all(len(c.closes) >= 1 for c in chatters), 30, "a socket of an old worker stayed open")
        answered_before = {c.name: len(c.answered) for c in chatters}
        wait_for(lambda: all(len(c.answered) > answered_before[c.name] for c in chatters), 60,
                 "a student could not chat again after the restart")
    finally:
        stop.set()
        for thread in threads:
            thread.join(60)

    events = _events(web["events"])
    leaving = sorted((t, pid) for t, event, pid in events if event == "leaves" and pid in old_workers)
    new_serving = sorted(t for t, event, pid in events if event == "serves" and pid not in old_workers)
    assert len(leaving) == WORKERS and len(new_serving) >= WORKERS, events
    for k, (left_at, pid) in enumerate(leaving, start=1):
        served_before = sum(1 for t in new_serving if t < left_at)
        assert served_before >= k, f"old worker {pid} was told to leave before a new worker served in its place"

    for chatter in chatters:
        assert chatter.closes[0] == 1012, (chatter.name, chatter.closes)
        assert chatter.unanswered == [] and chatter.errors == [], (chatter.name, chatter.unanswered, chatter.errors)
        assert set(chatter.written) == set(chatter.answered), chatter.name  # a line cut off was sent again
    with Session(web["engine"]) as session:
        stored = Counter(session.scalars(select(ChatMessage.body)))
        ids = dict(session.execute(select(ChatMessage.body, ChatMessage.id)).all())
    for chatter in chatters:
        for line, message_id in chatter.answered.items():
            assert ids.get(line) == message_id, f"{line!r} was answered but not stored"
        # A line without an answer was never read: sending it again stored it once, not twice.
        assert all(stored[line] == 1 for line in chatter.answered), (chatter.name, chatter.cut_off)
    assert http_failures == [] and set(http_answers) == {200}, http_failures[:5]
