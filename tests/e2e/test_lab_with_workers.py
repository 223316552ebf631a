"""`telelab up --workers 2` on PostgreSQL, as a person meets it: directly and through Debian's nginx configured as
the README shows (deploy/nginx/telelab.conf), in Chromium.

The lab runs as a real process with real gunicorn workers, its farm owner and its robots; a SIGHUP restarts the
workers while a student drives their practice robot, whose console reconnects by itself and keeps control.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import simple_websocket

from benchmarks.ports import free_port
from tests.conftest import ARTIFACTS_DIR, postgres_database
from tests.e2e.test_panels import odometry, wait_for

pytestmark = [pytest.mark.e2e, pytest.mark.postgres]

REPO = Path(__file__).resolve().parents[2]
NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
PASSWORD_LINE = re.compile(r"^\s+(student|tutor|admin)\s+\S+\s+password: (\S+)$")


@dataclass
class RunningLab:
    url: str
    process: subprocess.Popen[str]
    passwords: dict[str, str]
    database_url: str = ""
    output: list[str] = field(default_factory=list)
    robot_addresses: list[str] = field(default_factory=list)

    def worker_pids(self) -> set[int]:
        """The gunicorn workers: the launcher is gunicorn's master, and its workers are forks of it (its robots and
        its farm owner are other programs)."""
        launcher = _command(self.process.pid)
        return {pid for pid in _children(self.process.pid) if _command(pid) == launcher}


def _keep_reading(process: subprocess.Popen[str], output: list[str]) -> None:
    assert process.stdout is not None
    for line in process.stdout:
        output.append(line)


def _children(pid: int) -> list[int]:
    found = []
    for task in Path("/proc").glob("[0-9]*"):
        try:
            if int((task / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(task.name))
        except (OSError, ValueError, IndexError):
            continue
    return found


def _command(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode().strip()
    except OSError:
        return ""


def _answers(url: str) -> bool:
    try:
        with urllib.request.urlopen(url, timeout=2) as response:
            return response.status == 200
    except OSError:
        return False


def _listens(address: str) -> bool:
    host, port = address.rsplit(":", 1)
    with socket.socket() as probe:
        probe.settimeout(1)
        return probe.connect_ex((host, int(port))) == 0


@pytest.fixture(scope="module")
def lab() -> Iterator[RunningLab]:
    """The whole lab with two web workers on a fresh PostgreSQL database; stopped with Ctrl-C at the end."""
    with postgres_database() as database_url:
        port = free_port(neighbours=2)
        environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_TRUSTED_PROXIES": "1",
                       "PYTHONUNBUFFERED": "1"}
        process = subprocess.Popen(
            [str(Path(sys.executable).parent / "telelab"), "up", "--workers", "2", "--robots", "1",
             "--no-course-robots", "--no-demo-video", "--port", str(port)],
            cwd=REPO, env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        running = RunningLab(f"http://127.0.0.1:{port}", process, {}, database_url)
        assert process.stdout is not None
        for line in process.stdout:
            running.output.append(line)
            if (match := PASSWORD_LINE.match(line)) is not None:
                running.passwords[match[1]] = match[2]
            if (address := re.search(r"skill server at (\S+)", line)) is not None:
                running.robot_addresses.append(address[1])
            if len(running.passwords) == 3:
                break
        assert len(running.passwords) == 3, "".join(running.output)
        assert "with 2 web workers" in "".join(running.output)
        reader = threading.Thread(target=_keep_reading, args=(process, running.output), daemon=True)
        reader.start()  # the lab's log never fills the pipe, and a failure below can show it
        wait_for(lambda: process.poll() is not None or _answers(f"{running.url}/healthz"), 60,
                 "the lab's workers never answered")
        time.sleep(1)  # gunicorn halts when a worker fails to boot: the second worker has had its chance
        assert process.poll() is None, f"the lab stopped as it started:\n{''.join(running.output)}"
        try:
            yield running
        finally:
            process.send_signal(signal.SIGINT)
            process.wait(timeout=90)
            reader.join(timeout=10)
            process.stdout.close()
        assert process.returncode == 0, "".join(running.output)
        stopped = "".join(running.output).count("the lab has stopped")
        assert stopped == 1, "".join(running.output)  # the launcher stops it; its workers only leave
        assert not any(_listens(address) for address in running.robot_addresses), "a robot outlived the lab"


@pytest.fixture(scope="module")
def nginx(lab: RunningLab, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """Debian's nginx in front of the lab, with the README's site configuration and only its ports changed."""
    if not os.path.exists(NGINX):
        pytest.fail(f"{NGINX} is missing: `make test` installs Debian's nginx package.")
    prefix = tmp_path_factory.mktemp("nginx")
    port = free_port()
    site = (REPO / "deploy" / "nginx" / "telelab.conf").read_text()
    site = site.replace("server 127.0.0.1:5000;", f"server {lab.url.removeprefix('http://')};")
    site = site.replace("listen 8080;", f"listen 127.0.0.1:{port};")
    (prefix / "telelab.conf").write_text(site)
    (prefix / "nginx.conf").write_text(
        ("user root;\n" if os.geteuid() == 0 else "")
        + f"pid {prefix}/nginx.pid;\nerror_log {prefix}/error.log;\nevents {{}}\n"
        + f"http {{\n  access_log off;\n  client_body_temp_path {prefix}/body;\n  proxy_temp_path {prefix}/proxy;\n"
        + f"  include {prefix}/telelab.conf;\n}}\n")
    server = subprocess.Popen([NGINX, "-p", str(prefix), "-c", str(prefix / "nginx.conf"), "-g", "daemon off;"],
                              stderr=subprocess.PIPE, text=True)
    url = f"http://127.0.0.1:{port}"
    try:
        wait_for(lambda: server.poll() is not None or _answers(f"{url}/healthz"), 20, "nginx never answered")
        assert server.poll() is None, f"nginx did not start: {server.stderr.read() if server.stderr else ''}"
        yield url
    finally:
        server.terminate()
        server.communicate(timeout=10)  # reaps it and closes the pipe


def _log_in(page, url: str, username: str, password: str) -> None:
    page.goto(f"{url}/login")
    page.fill("#username", username)
    page.fill("#password", password)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()


def _open_practice_console(page, url: str) -> None:
    page.goto(f"{url}/practice")
    start = page.get_by_role("button", name="Start my practice robot")
    page.locator("#practice[data-running=true], #practice [data-action=start]:visible").first.wait_for()
    if start.is_visible():
        start.click()
    page.locator("#practice[data-running=true]").wait_for(timeout=60_000)
    page.get_by_role("link", name="Open in the console").click()
    page.wait_for_url("**/lab/practice-student")
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
    page.locator('queue-panel[data-role="controller"]').wait_for(timeout=30_000)
    wait_for(lambda: not math.isnan(odometry(page, "x")), 20, "the practice robot's odometry shows no numbers")


def test_a_rolling_restart_of_the_workers_reconnects_the_console_and_keeps_the_practice_robot(
        page, lab: RunningLab) -> None:
    _log_in(page, lab.url, "student", lab.passwords["student"])
    _open_practice_console(page, lab.url)
    page.locator("body").click(position={"x": 5, "y": 5})
    page.keyboard.down("ArrowUp")  # the old workers number some commands first: the new ones must number above
    try:
        wait_for(lambda: _drive_pad_figures(page)[0] >= 40, 15, "the console sent no commands before the restart")
    finally:
        page.keyboard.up("ArrowUp")
    time.sleep(0.5)
    acknowledged_before, _ = _drive_pad_figures(page)
    page.evaluate("""() => {
        window.drivePhases = [];
        const line = document.querySelector('[data-connection="drive"]');
        new MutationObserver(() => window.drivePhases.push(line.dataset.phase))
            .observe(line, { attributes: true, attributeFilter: ["data-phase"] });
    }""")
    before = lab.worker_pids()
    assert len(before) == 2, f"expected two workers, found {before}"

    lab.process.send_signal(signal.SIGHUP)  # gunicorn's rolling restart: new workers, the old ones leave
    wait_for(lambda: len(lab.worker_pids() - before) == 2 and not lab.worker_pids() & before, 60,
             "the workers were not replaced")
    wait_for(lambda: "open" in page.evaluate("window.drivePhases"), 30, "the console never reconnected")
    phases = page.evaluate("window.drivePhases")
    assert "reconnecting" in phases or "connecting" in phases, phases
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
    page.locator('queue-panel[data-role="controller"]').wait_for(timeout=30_000)
    assert page.locator("[data-connection][data-phase=closed]").count() == 0  # nothing gave up for good
    x_before = odometry(page, "x")
    page.locator("body").click(position={"x": 5, "y": 5})
    page.keyboard.down("ArrowUp")
    try:
        # The new socket numbers from 1 again: an acknowledgement below the old ones is the new socket's.
        wait_for(lambda: 1 <= _drive_pad_figures(page)[0] < acknowledged_before, 15,
                 "no command was acknowledged after the restart")
        acknowledged, applied = _drive_pad_figures(page)
        assert applied == acknowledged, f"command {acknowledged} was acknowledged but {applied} is in force"
        wait_for(lambda: abs(odometry(page, "x") - x_before) > 0.02, 15,
                 "the practice robot did not move after the restart")
    finally:
        page.keyboard.up("ArrowUp")


def _drive_pad_figures(page) -> tuple[int, int]:
    """The drive pad's last acknowledged command and the command the robot has in force, as its line reads them
    (-1 while none)."""
    figures = page.evaluate("""() => ["ack-sequence", "applied-sequence"].map(
        (name) => document.querySelector(`drive-pad [data-field="${name}"]`)?.textContent ?? "")""")
    return tuple(int(figure) if figure.strip().isdigit() else -1 for figure in figures)  # type: ignore[return-value]


def test_through_nginx_the_camera_streams_and_a_chat_message_reaches_a_phone(
        chromium, page, lab: RunningLab, nginx: str) -> None:
    phone_context = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    phone = phone_context.new_page()
    try:
        _log_in(page, nginx, "student", lab.passwords["student"])
        _log_in(phone, nginx, "tutor", lab.passwords["tutor"])
        for tab in (page, phone):
            tab.goto(f"{nginx}/lab/lab-1")
            tab.get_by_role("tab", name="Chat").click()
            tab.locator("#chat-input:enabled").wait_for(timeout=30_000)
        page.locator('[data-connection="camera"][data-phase="open"]').wait_for(timeout=30_000)
        frame = page.locator('[data-field="frame-sequence"]').first
        wait_for(lambda: (frame.text_content() or "").strip().isdigit() and int(frame.text_content()) > 3, 20,
                 "no camera frames came through nginx")
        page.get_by_label("Message to everyone on this robot").fill("through the proxy")
        page.keyboard.press("Enter")
        phone.locator('chat-panel [data-field="chat-body"]', has_text="through the proxy").wait_for(timeout=15_000)
        phone.screenshot(path=str(ARTIFACTS_DIR / "nginx-chat-phone.png"))
        page.screenshot(path=str(ARTIFACTS_DIR / "nginx-console-desktop.png"))
    finally:
        phone_context.close()


def test_a_worker_killed_mid_attempt_leaves_the_attempt_graded_on_the_whole_run(lab: RunningLab) -> None:
    from sqlalchemy import create_engine, select

    from middleware.models.assessment import Attempt
    from tests.conftest import LabClient
    from tests.integration.bookings.conftest import api
    from tests.integration.lab.test_robot_channels import drive_for, receive_json

    student = LabClient(lab.url)
    assert student.login("student", lab.passwords["student"]) == 302
    exams = [exam for course_id in (1, 2, 3) for exam in api(student, "GET", f"/api/courses/{course_id}/exams")[1]
             .get("exams", [])]
    exam = next(exam for exam in exams if exam["kind"] == "experimental")
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    status, answer = api(student, "POST", f"/api/exams/{exam['id']}/attempts")
    assert status == 201, answer
    attempt_id = answer["attempt"]["id"]
    drive_for(drive, 1.0, 0.2, 0.0, 1)
    os.kill(sorted(lab.worker_pids())[0], signal.SIGKILL)  # a worker dies mid-attempt, whatever it held
    time.sleep(3.0)
    with contextlib.suppress(simple_websocket.ConnectionClosed):  # it was on the worker that died, or not
        drive.close()
    drive = student.websocket("/ws/robots/lab-1/drive")  # the page reconnects; the seat waited for it
    ready = receive_json(drive)
    assert ready["type"] == "ready" and ready["is_controller"], ready
    drive_for(drive, 1.0, 0.2, 0.0, 1)
    status, answer = api(student, "POST", f"/api/attempts/{attempt_id}/submit")
    drive.close()
    assert status == 200, answer
    engine = create_engine(lab.database_url)
    try:
        with engine.connect() as connection:
            trace = connection.scalar(select(Attempt.trace).where(Attempt.id == attempt_id))
    finally:
        engine.dispose()
    gaps = [later[0] - earlier[0] for earlier, later in zip(trace, trace[1:], strict=False)]
    assert trace[0][0] < 0.5 and trace[-1][0] > 4.0 and max(gaps) < 0.5, "the whole run, across the dead worker"
    assert any(row["item"] == "task" for row in answer["attempt"]["results"])
