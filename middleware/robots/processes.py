"""A skill server as a child process: start, wait for SERVING, watch and restart, stop.

Used by `telelab up`, practice robots, the demo-video recorder, tests and benchmarks; nothing else in the
middleware starts a skill server.
"""

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

LISTENING_LINE = re.compile(r"listening on (?P<address>\S+:\d+)")
START_TIMEOUT_S = 60.0
RESTART_PAUSE_S = 1.0
CONTROLLER_TOKEN_VARIABLE = "TELELAB_CONTROLLER_TOKEN"  # skill_server/server.py reads it


class SkillServerStartError(RuntimeError):
    """A skill server did not start; the message says which and why."""


@dataclass
class SkillServerProcess:
    """One robot's skill server, run as a child process and restarted if it dies (unless restart is off).

    echo prints the server's output prefixed with its name (the launcher's console); otherwise it is
    drained and dropped, so a full pipe never blocks the server.
    """

    name: str
    scene: str
    restart: bool = True
    echo: bool = True
    controller_token: str = ""  # obeyed from the start, and again after a restart
    host: str = "127.0.0.1"  # the address it listens on
    exit_with_parent: bool = False  # the server stops when this process dies (a farm actor killed)
    fast: bool = False  # its world steps as fast as possible (`--fast`), not in real time
    address: str = ""
    process: subprocess.Popen[str] | None = None
    stopping: bool = False
    restarts: int = 0
    _watcher: threading.Thread | None = field(default=None, repr=False)
    _guard: threading.Lock = field(default_factory=threading.Lock, repr=False)  # stopping vs a (re)start

    def start(self, port: int = 0) -> None:
        """Starts the process and waits for the line that gives its address."""
        command = [sys.executable, "-m", "skill_server", "--port", str(port), "--name", self.name,
                   "--scene", self.scene, "--host", self.host]
        if self.exit_with_parent:
            command += ["--parent-pid", str(os.getpid())]
        if self.fast:
            command.append("--fast")
        # A new session: Ctrl-C reaches only the parent, which then stops the children in order.
        environment = {**os.environ, CONTROLLER_TOKEN_VARIABLE: self.controller_token}
        with self._guard:  # a stop() that came first wins: no process starts after it
            if self.stopping:
                raise SkillServerStartError(f"The skill server of {self.name} was stopped while it started.")
            self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                            start_new_session=True, env=environment)
        deadline = time.monotonic() + START_TIMEOUT_S
        assert self.process.stdout is not None
        while time.monotonic() < deadline:
            line = self.process.stdout.readline()
            if not line:
                raise SkillServerStartError(
                    f"The skill server of {self.name} exited while starting (code {self.process.wait()}). "
                    "Run `telelab skill-server --port 0` to see why.")
            match = LISTENING_LINE.search(line)
            if match:
                self.address = match["address"]
                break
        else:
            raise SkillServerStartError(f"The skill server of {self.name} did not start within "
                                        f"{START_TIMEOUT_S:.0f} s.")
        self._watcher = threading.Thread(target=self._watch, name=f"watch-{self.name}", daemon=True)
        self._watcher.start()

    def serve(self) -> str:
        """Starts the process and waits until it reports SERVING; its address."""
        self.start()
        try:
            wait_until_serving(self.address)
        except SkillServerStartError:
            self.stop()
            raise
        return self.address

    def _watch(self) -> None:
        process = self.process
        assert process is not None and process.stdout is not None
        with process.stdout:
            for line in process.stdout:
                if self.echo:
                    print(f"[{self.name}] {line}", end="", flush=True)
        code = process.wait()
        if self.stopping or not self.restart:
            return
        print(f"[{self.name}] skill server exited with code {code}; restarting it", flush=True)
        self.restarts += 1
        time.sleep(RESTART_PAUSE_S)
        try:
            self.start(port=int(self.address.rsplit(":", 1)[1]))
        except SkillServerStartError as error:
            print(f"[{self.name}] {error}", flush=True)

    def stop(self, timeout_s: float = 5.0) -> None:
        """Asks the process to stop (SIGTERM), then kills it if it does not."""
        with self._guard:
            self.stopping = True
            process = self.process
        if process is None:
            return
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        if self._watcher is not None and self._watcher is not threading.current_thread():
            self._watcher.join(timeout_s)
        elif self._watcher is None and process.stdout is not None:
            process.stdout.close()  # a start that failed: no watcher ever read (and closed) the pipe


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
    raise SkillServerStartError(f"The skill server at {address} did not report SERVING within {timeout_s:.0f} s.")
