"""The local farm shared by the web workers of one host: one owner process holds the robots, workers ask it.

`telelab up --workers N` starts the owner before the workers (a child of the launcher, listening on a Unix
socket in a private temporary folder, calls authenticated with a key only the launcher's children know) and
names it in TELELAB_LOCAL_FARM / TELELAB_LOCAL_FARM_KEY. A worker's local farm is then a client of the owner, so every
worker sees and reaches the same practice, class and pool robots, and a worker that dies or is replaced in a
rolling restart takes no robot with it. The owner's robots stop with it; it stops when the launcher dies.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from multiprocessing import AuthenticationError
from multiprocessing.managers import BaseManager, BaseProxy
from pathlib import Path

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.config import ConfigError
from middleware.farm.base import Capacity, FarmRobot, FarmUnavailable, RobotSpec
from middleware.farm.local import LocalProcessFarm

ADDRESS_VARIABLE = "TELELAB_LOCAL_FARM"
KEY_VARIABLE = "TELELAB_LOCAL_FARM_KEY"
FARM_METHODS = ("start", "find", "stop", "robots", "capacity")

LAUNCHER_VARIABLE = "TELELAB_FARM_LAUNCHER_PID"
START_TIMEOUT_S = 30.0


class _FarmManager(BaseManager):
    pass


_owned: list = []  # in the owner process: its LocalProcessFarm


_FarmManager.register("farm", callable=lambda: _owned[0], exposed=FARM_METHODS)


def serve_owner() -> None:
    """The owner process (`python -m middleware.farm.owner`): the farm, stopped with the process or the launcher."""
    launcher_pid = int(os.environ[LAUNCHER_VARIABLE])
    farm = LocalProcessFarm()
    _owned.append(farm)

    def leave(*_args: object) -> None:
        farm.close()
        os._exit(0)

    def leave_with_launcher() -> None:
        while os.getppid() == launcher_pid:
            time.sleep(1.0)
        leave()

    signal.signal(signal.SIGTERM, leave)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the launcher, which stops us in order
    threading.Thread(target=leave_with_launcher, name="farm-owner-watch", daemon=True).start()
    server = _FarmManager(address=os.environ[ADDRESS_VARIABLE], authkey=bytes.fromhex(os.environ[KEY_VARIABLE])
                          ).get_server()
    server.serve_forever()


class FarmOwner:
    """The launcher's handle on the owner process: start it, name it to the workers, stop it."""

    def __init__(self) -> None:
        self._folder = Path(tempfile.mkdtemp(prefix="telelab-farm-"))  # mode 0700: this account only
        self.address = str(self._folder / "farm.sock")
        self.key = os.urandom(32)
        self._process: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        """Starts the owner, waits until it answers, and sets TELELAB_LOCAL_FARM(_KEY) for the workers."""
        environment = {**os.environ, ADDRESS_VARIABLE: self.address, KEY_VARIABLE: self.key.hex(),
                       LAUNCHER_VARIABLE: str(os.getpid())}
        self._process = subprocess.Popen([sys.executable, "-m", "middleware.farm.owner"], env=environment)
        deadline = time.monotonic() + START_TIMEOUT_S
        while not SharedLocalFarm(self.address, self.key.hex()).answers():
            if self._process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise FarmUnavailable(gettext("The lab's robot farm process did not start; its error is printed "
                                              "above."))
            time.sleep(0.1)
        os.environ.update({ADDRESS_VARIABLE: self.address, KEY_VARIABLE: self.key.hex()})

    def stop(self) -> None:
        """Stops the owner and, with it, every robot it runs."""
        if self._process is not None and self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(30)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        shutil.rmtree(self._folder, ignore_errors=True)
        os.environ.pop(ADDRESS_VARIABLE, None)
        os.environ.pop(KEY_VARIABLE, None)


class SharedLocalFarm:
    """A worker's local farm: every call goes to the owner process; robots outlive this worker."""

    backend = "local"

    def __init__(self, address: str, key_hex: str) -> None:
        try:
            key = bytes.fromhex(key_hex)
        except ValueError:
            raise ConfigError(f"{KEY_VARIABLE} must be the hex key `telelab up` gave its workers.") from None
        self.address = address
        self._manager = _FarmManager(address=address, authkey=key)
        self._farm = None
        self._connected_in: int | None = None  # the process whose connection the proxy holds
        self._lock = threading.Lock()

    def _call(self, method: str, *args: object):
        try:
            with self._lock:
                # A fork (gunicorn's workers of the launcher that started the lab) inherits the proxy's socket: two
                # processes reading one connection unpickle each other's answers. Each process connects its own.
                if self._farm is None or self._connected_in != os.getpid():
                    if self._connected_in not in (None, os.getpid()):
                        # Proxies share one connection per address and thread, kept by class: a fork's new proxy
                        # would reuse the inherited one (multiprocessing resets it only in the processes it forks).
                        BaseProxy._address_to_local.pop(self.address, None)
                    self._manager.connect()
                    self._farm = self._manager.farm()  # type: ignore[attr-defined]
                    self._connected_in = os.getpid()
            return getattr(self._farm, method)(*args)
        except (OSError, EOFError, AuthenticationError) as error:
            with self._lock:
                self._farm = None
            raise FarmUnavailable(gettext("The lab's robot farm process is not running; restart the lab (`telelab "
                                          "up`). (%(error)s)", error=error.__class__.__name__)) from None

    def start(self, spec: RobotSpec) -> FarmRobot:
        return self._call("start", spec)

    def find(self, name: str) -> FarmRobot | None:
        return self._call("find", name)

    def stop(self, name: str) -> bool:
        return self._call("stop", name)

    def robots(self) -> list[FarmRobot]:
        return self._call("robots")

    def capacity(self) -> Capacity:
        return self._call("capacity")

    def answers(self) -> bool:
        """Whether the owner process is up and accepts this key."""
        try:
            self._call("capacity")
        except FarmUnavailable:
            return False
        return True

    def close(self) -> None:
        """A worker leaving lets go of the owner only: its robots run on for the other workers."""
        with self._lock:
            self._farm = None


if __name__ == "__main__":
    serve_owner()
