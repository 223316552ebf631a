"""The recording writer: one child process per worker (writer.main, started by WriterProcess), which does all of the
recorder's work but the tap, so none of it holds the worker's interpreter. Once a second the worker's keeper hands
it one tick (recorder.py): the command notes the worker saw, each tapped session's second of messages (references
the channel loop kept, as the hubs packed them for viewers), and which robots of the open recordings the worker
reaches and watches. The child (keeping.py) logs the notes, decodes and encodes each second as protobuf, adds it to
its MCAP part (files.PartWriter: chunking, zstd), closes the chunk with an fsync, heartbeats and claims sessions in
the database, opens, completes and sweeps recordings when elected, and answers which sessions the worker taps now.
A crash of the worker, of the writer or of the machine loses at most the second in progress.

The wire: a 4-byte big-endian length and a pickle, both ways, over the child's stdin and stdout (only this module
talks on them). The child ends its parts (closed without a summary: `files.read_part` reads them) and exits when its
stdin ends, so a killed worker leaves no writer behind.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import struct
import subprocess
import sys
import threading
from pathlib import Path
from typing import IO, Any

from middleware.db import make_engine
from middleware.recordings.keeping import Keeping, Settings

log = logging.getLogger(__name__)
NICENESS = 10  # the writer child's, above its worker's: at nice 10 it gets about a tenth of a core both want


class WriterGone(RuntimeError):
    """The writer process died or its pipe broke: its parts end at their last chunk; the sessions go on anew."""


class WriterRefused(RuntimeError):
    """The writer failed a request (the database away for a moment): its parts stay open; the next tick goes on."""


class WriterProcess:
    """This worker's writer child, started on first use (and again after a crash); every call waits for its answer,
    on the keeper's thread, never on the loop."""

    def __init__(self, database_url: str, settings: dict[str, Any] | None = None) -> None:
        self._database_url = database_url
        self.settings = settings or {}  # keeping.Settings' fields, told to each child once
        self._lock = threading.Lock()
        self._child: subprocess.Popen[bytes] | None = None
        self._configured: subprocess.Popen[bytes] | None = None  # the child that was told the database and settings
        self.starts = 0

    @property
    def pid(self) -> int | None:
        """The child's pid while it runs."""
        child = self._child
        return child.pid if child is not None and child.poll() is None else None

    def start(self) -> None:
        """Starts the child unless it runs (it imports while the caller goes on; the first call waits for it)."""
        with self._lock:
            if self._child is None or self._child.poll() is not None:
                self._start_locked()

    def tick(self, tick: dict[str, Any]) -> dict[str, Any]:
        """A tick (keeping.Keeping.tick): notes, seconds, the robots reached; the sessions to tap now."""
        return self._call(("tick", tick))

    def sweep(self) -> list[int]:
        """The retention and disk limits applied now; the ids removed."""
        return self._call(("sweep",))

    def stop(self) -> None:
        """Ends the child (it closes what is open) and waits for it."""
        with self._lock:
            child, self._child = self._child, None
        if child is None:
            return
        if child.stdin is not None:
            with contextlib.suppress(OSError):
                child.stdin.close()
        try:
            child.wait(10)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait(5)
        if child.stdout is not None:
            child.stdout.close()

    def _call(self, request: tuple[Any, ...]) -> Any:
        with self._lock:
            child = self._child
            if child is None or child.poll() is not None:
                if child is not None and self._configured is child:  # it had parts: their sessions go on anew
                    self._forget_locked(child)
                    self._child = None
                    raise WriterGone("the recording writer died")
                child = self._start_locked()
            if self._configured is not child:
                self._exchange_locked(child, ("configure", self._database_url, self.settings))
                self._configured = child
            return self._exchange_locked(child, request)

    def _exchange_locked(self, child: subprocess.Popen[bytes], request: tuple[Any, ...]) -> Any:
        assert child.stdin is not None and child.stdout is not None
        try:
            _send(child.stdin, request)
            answer = _receive(child.stdout)
        except (OSError, EOFError, pickle.UnpicklingError) as error:
            self._forget_locked(child)
            self._child = None
            raise WriterGone(f"the recording writer is gone ({error})") from error
        if not isinstance(answer, tuple) or answer[0] != "ok":
            raise WriterRefused(f"the recording writer refused {request[0]}: {answer}")
        return answer[1]

    def _start_locked(self) -> subprocess.Popen[bytes]:
        if self._child is not None:
            self._forget_locked(self._child)
        self._child = subprocess.Popen(  # noqa: S603 - this interpreter and this module, no shell
            [sys.executable, "-c", "from middleware.recordings.writer import main; main()"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=str(Path(__file__).resolve().parents[2]), close_fds=True)
        self.starts += 1
        return self._child

    @staticmethod
    def _forget_locked(child: subprocess.Popen[bytes]) -> None:
        for stream in (child.stdin, child.stdout):
            if stream is not None:
                with contextlib.suppress(OSError):
                    stream.close()
        if child.poll() is None:
            child.kill()
        child.wait(5)


def _send(stream: IO[bytes], value: object) -> None:
    data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(struct.pack(">I", len(data)) + data)
    stream.flush()


def _receive(stream: IO[bytes]) -> Any:
    header = stream.read(4)
    if len(header) < 4:
        raise EOFError("the pipe ended")
    (length,) = struct.unpack(">I", header)
    data = stream.read(length)
    if len(data) < length:
        raise EOFError("the pipe ended mid-message")
    return pickle.loads(data)  # noqa: S301 - the parent process, over its own pipe


# The child's side.


def serve(requests: IO[bytes], answers: IO[bytes]) -> None:
    """The child's loop: one answer per request until the requests end; then every open part is closed."""
    keeping: Keeping | None = None
    try:
        while True:
            try:
                request = _receive(requests)
            except EOFError:
                return
            try:
                if request[0] == "configure":
                    if keeping is None:
                        settings = dict(request[2])
                        settings["directory"] = Path(settings["directory"])
                        keeping = Keeping(make_engine(request[1], pool_size=2, max_overflow=1), Settings(**settings))
                    answer: object = ("ok", None)
                elif keeping is None:
                    raise RuntimeError("not configured")
                elif request[0] == "tick":
                    answer = ("ok", keeping.tick(request[1]))
                elif request[0] == "sweep":
                    answer = ("ok", keeping.sweep())
                else:
                    raise ValueError(f"unknown request {request[0]!r}")
            except Exception as error:  # noqa: BLE001 - said to the keeper, which goes on at its next tick
                log.exception("recording writer: %s failed", request[0])
                answer = f"{type(error).__name__}: {error}"
            _send(answers, answer)
    finally:
        if keeping is not None:
            keeping.close()
            keeping.engine.dispose()


def main() -> None:
    """The child's entry: serves the parent on stdin/stdout."""
    logging.basicConfig(level=logging.WARNING)
    with contextlib.suppress(OSError):  # recording is background work: a core both want goes to the live path first
        os.nice(NICENESS)
    requests, answers = sys.stdin.buffer, sys.stdout.buffer
    sys.stdout = sys.stderr  # nothing but answers on the answers' pipe
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    serve(requests, answers)
