"""`telelab up`: the whole lab on one machine — skill servers as child processes, then the web tier."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field

import grpc
from grpc_health.v1 import health_pb2, health_pb2_grpc

from middleware.models import Role

LISTENING_LINE = re.compile(r"listening on (?P<address>\S+:\d+)")
DEMO_ACCOUNTS = (("student", Role.STUDENT), ("tutor", Role.TUTOR), ("admin", Role.ADMIN))
# The teleoperation-under-delay experiment's robots (thesis chapter 4): one per course scene, idle until driven.
COURSE_ROBOTS = (("course-a", "course-A"), ("course-b", "course-B"))
START_TIMEOUT_S = 60.0


class LabStartError(RuntimeError):
    """A part of the lab did not start; the message says which and why."""


class LabStopRequested(Exception):
    """SIGTERM (a service manager, `kill`) or SIGHUP (the terminal closed): stop as Ctrl-C does."""


def _request_stop(signum: int, _frame: object) -> None:
    signal.signal(signum, signal.SIG_IGN)  # a second signal must not cut the children's shutdown short
    raise LabStopRequested(signal.Signals(signum).name)


def stop_on_termination_signals() -> None:
    """Turns SIGTERM and SIGHUP into LabStopRequested in the main thread, so the skill servers are stopped
    instead of left running without their parent."""
    signal.signal(signal.SIGTERM, _request_stop)
    signal.signal(signal.SIGHUP, _request_stop)


@dataclass
class SkillServerProcess:
    """One robot's skill server, run as a child process and restarted if it dies."""

    name: str
    scene: str
    address: str = ""
    process: subprocess.Popen[str] | None = None
    stopping: bool = False
    restarts: int = 0
    _watcher: threading.Thread | None = field(default=None, repr=False)

    def start(self, port: int = 0) -> None:
        """Starts the process and waits for the line that gives its address."""
        command = [sys.executable, "-m", "skill_server", "--port", str(port), "--name", self.name,
                   "--scene", self.scene]
        # A new session: Ctrl-C reaches only `telelab up`, which then stops the children in order.
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                        start_new_session=True)
        deadline = time.monotonic() + START_TIMEOUT_S
        assert self.process.stdout is not None
        while time.monotonic() < deadline:
            line = self.process.stdout.readline()
            if not line:
                raise LabStartError(f"The skill server of {self.name} exited while starting (code "
                                    f"{self.process.wait()}). Run `telelab skill-server --port 0` to see why.")
            match = LISTENING_LINE.search(line)
            if match:
                self.address = match["address"]
                break
        else:
            raise LabStartError(f"The skill server of {self.name} did not start within {START_TIMEOUT_S:.0f} s.")
        self._watcher = threading.Thread(target=self._watch, name=f"watch-{self.name}", daemon=True)
        self._watcher.start()

    def _watch(self) -> None:
        process = self.process
        assert process is not None and process.stdout is not None
        with process.stdout:
            for line in process.stdout:
                print(f"[{self.name}] {line}", end="", flush=True)
        code = process.wait()
        if not self.stopping:
            print(f"[{self.name}] skill server exited with code {code}; restarting it", flush=True)
            self.restarts += 1
            time.sleep(1.0)
            if not self.stopping:
                self.start(port=int(self.address.rsplit(":", 1)[1]))

    def stop(self, timeout_s: float = 5.0) -> None:
        """Asks the process to stop (SIGTERM), then kills it if it does not."""
        self.stopping = True
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self._watcher is not None:
            self._watcher.join(timeout_s)


def wait_until_serving(address: str, timeout_s: float = START_TIMEOUT_S) -> None:
    """Blocks until the skill server at address reports SERVING through gRPC health checking."""
    deadline = time.monotonic() + timeout_s
    with grpc.insecure_channel(address) as channel:
        stub = health_pb2_grpc.HealthStub(channel)
        while time.monotonic() < deadline:
            try:
                reply = stub.Check(health_pb2.HealthCheckRequest(service=""), timeout=1.0)
                if reply.status == health_pb2.HealthCheckResponse.SERVING:
                    return
            except grpc.RpcError:
                pass
            time.sleep(0.2)
    raise LabStartError(f"The skill server at {address} did not report SERVING within {timeout_s:.0f} s.")


def ensure_demo_accounts(app) -> list[tuple[str, str, str]]:  # type: ignore[no-untyped-def]
    """Creates the demo accounts that do not exist yet; returns (name, role, password) of the new ones."""
    from middleware.auth.services import create_user, find_user, generate_password
    from middleware.db import session_factory

    created = []
    with session_factory(app)() as session:
        for name, role in DEMO_ACCOUNTS:
            if find_user(session, name) is None:
                password = generate_password()
                create_user(session, name, role, password)
                created.append((name, role.value, password))
        session.commit()
    return created


def seed_demo_content(app) -> list[str]:  # type: ignore[no-untyped-def]
    """The teaching area's demo data: example tours and a lesson whose video is recorded from the simulator."""
    from middleware.tours.demo import seed_demo_content as seed

    return seed(app)


def lab_robots(robot_count: int, scene: str, course_robots: bool = True) -> list[SkillServerProcess]:
    """The skill servers `telelab up` runs: lab-1..lab-N in scene, then the experiment's course robots."""
    robots = [SkillServerProcess(f"lab-{i + 1}", scene) for i in range(robot_count)]
    if course_robots:
        robots += [SkillServerProcess(name, course_scene) for name, course_scene in COURSE_ROBOTS]
    return robots


def run_lab(host: str, port: int, robot_count: int, scene: str, course_robots: bool = True) -> int:
    """Starts skill servers, migrates the database, creates demo accounts, and serves until Ctrl-C or SIGTERM."""
    from middleware import create_app
    from middleware.db import upgrade_to_head
    from middleware.serve import serve_forever

    robots = lab_robots(robot_count, scene, course_robots)
    stop_on_termination_signals()
    try:
        for robot in robots:
            robot.start()
            wait_until_serving(robot.address)
            print(f"robot {robot.name}: skill server at {robot.address} (scene {robot.scene})", flush=True)
        os.environ["TELELAB_ROBOTS"] = ",".join(f"{r.name}={r.address}" for r in robots)
        app = create_app()
        upgrade_to_head(app.config["DATABASE_URL"])
        created = ensure_demo_accounts(app)
        seed_demo_content(app)
        _print_banner(host, port, created)
        serve_forever(app, host, port)
    except LabStartError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, LabStopRequested):
        print("\nstopping the lab", flush=True)
    finally:
        for robot in robots:
            robot.stop()
    print("the lab has stopped", flush=True)
    return 0


def _print_banner(host: str, port: int, created: list[tuple[str, str, str]]) -> None:
    lines = ["", f"Telelab is running at http://{host}:{port}  (Ctrl-C stops it)"]
    if created:
        lines.append("Demo accounts (the passwords are shown only this once; "
                     "change one with `telelab users set-password NAME`):")
        lines += [f"  {role:8} {name:10} password: {password}" for name, role, password in created]
    else:
        lines.append("The demo accounts student, tutor and admin exist already; "
                     "`telelab users set-password NAME` gives one a new password.")
    print("\n".join(lines) + "\n", flush=True)
