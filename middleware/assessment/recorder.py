"""Records what the robot did during an experimental attempt: ground truth and odometry, a few samples a second.

One recorder per attempt in progress in this process, a task on the process's channel loop (live/loop.py) reading
its own grpc.aio telemetry stream (the fan-out hub's messages carry no ground truth): no thread of its own; its
flushes to the database run on the loop's shared pool. The samples are stored in the attempt every FLUSH_S, with the
time, so another worker can grade an attempt it did not record; when a worker dies mid-attempt, another takes the
recording over once it has been quiet for STALE_S (`RecordingKeeper`), continuing the stored trace. What arrived after
the dead worker's last flush is a gap in the trace, at most FLUSH_S + STALE_S + CHECK_S long.
"""

from __future__ import annotations

import asyncio
import logging
import os
import socket
import threading
import time
from collections.abc import Callable

from middleware.assessment.trace_grading import MAX_TRACE_SAMPLES
from middleware.live.loop import channel_loop
from middleware.robots.link import RobotLink

log = logging.getLogger(__name__)
RATE_HZ = 5.0
FLUSH_S = 2.0
STALE_S = 3 * FLUSH_S  # a recorder not heard of for this long has died with its process
CHECK_S = 4.0  # how often each worker looks for attempts whose recorder died


def process_key() -> str:
    """This process, as the recorder of an attempt."""
    return f"{socket.gethostname()[:60]}:{os.getpid()}"


class TraceRecorder:
    """Samples [t_s, gx, gy, gth, ox, oy, oth] from the robot's telemetry until stopped."""

    def __init__(self, link: RobotLink, flush: Callable[[list[list[float]]], bool],
                 initial: list[list[float]] | None = None, loop: asyncio.AbstractEventLoop | None = None) -> None:
        self._link, self._flush = link, flush
        self._samples: list[list[float]] = [list(sample) for sample in (initial or [])]
        # A recording taken over goes on from the stored trace's time (the gap while nobody recorded stays a gap).
        self._offset_s = self._samples[-1][0] + 1.0 / RATE_HZ if self._samples else 0.0
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self._ended = threading.Event()
        self._started = time.monotonic()
        self._loop = loop or channel_loop().loop
        self._future = asyncio.run_coroutine_threadsafe(self._run(), self._loop)

    def samples(self) -> list[list[float]]:
        """A copy of the samples so far."""
        with self._lock:
            return [list(s) for s in self._samples]

    def stop(self) -> list[list[float]]:
        """Stops recording and returns every sample (waits for the recording to end, unless called on its loop)."""
        self._stopped.set()
        try:
            self._loop.call_soon_threadsafe(self._future.cancel)
        except RuntimeError:  # the loop has stopped: nothing records any more
            self._ended.set()
        if not self._on_own_loop():
            self._ended.wait(timeout=3)
        return self.samples()

    def _on_own_loop(self) -> bool:
        try:
            return asyncio.get_running_loop() is self._loop
        except RuntimeError:
            return False

    async def _run(self) -> None:
        last_flush = time.monotonic()
        updates = self._link.watch_telemetry(RATE_HZ)
        try:
            async for message in updates:
                if self._stopped.is_set():
                    break
                truth, odometry = message.ground_truth, message.odometry.pose
                sample = [round(self._offset_s + time.monotonic() - self._started, 3), round(truth.x_m, 4),
                          round(truth.y_m, 4),
                          round(truth.theta_rad, 4), round(odometry.x_m, 4), round(odometry.y_m, 4),
                          round(odometry.theta_rad, 4)]
                with self._lock:
                    self._samples.append(sample)
                    del self._samples[:-MAX_TRACE_SAMPLES]
                if time.monotonic() - last_flush >= FLUSH_S:
                    last_flush = time.monotonic()
                    # The database write blocks: on the loop's shared pool, never on the loop.
                    if not await asyncio.get_running_loop().run_in_executor(None, self._flush, self.samples()):
                        break  # the attempt ended elsewhere
        except asyncio.CancelledError:
            pass  # stopped
        except Exception as error:  # a broken stream ends the recording
            if not self._stopped.is_set():
                log.warning("trace recording on %s stopped: %s", self._link.name, error)
        finally:
            await updates.aclose()
            self._ended.set()


_recorders: dict[int, TraceRecorder] = {}
_recorders_lock = threading.Lock()


def start(attempt_id: int, link: RobotLink, flush: Callable[[list[list[float]]], bool],
          initial: list[list[float]] | None = None) -> None:
    """Starts recording for the attempt (after the stored samples initial) unless this process records it already."""
    with _recorders_lock:
        if attempt_id not in _recorders:
            _recorders[attempt_id] = TraceRecorder(link, flush, initial)


def stop(attempt_id: int) -> list[list[float]] | None:
    """Stops the attempt's recorder; its samples, or None when this process was not recording it."""
    with _recorders_lock:
        recorder = _recorders.pop(attempt_id, None)
    return recorder.stop() if recorder is not None else None


class RecordingKeeper:
    """Takes over, every CHECK_S, the recordings of attempts whose recorder went quiet (its worker died). Each worker
    that has recorded an attempt runs one; the claim is a conditional UPDATE, so one worker wins each attempt. (The
    grade itself comes from the robot's pose log; a recording matters when the robot restarted meanwhile.)"""

    def __init__(self, find_orphans: Callable[[], list[tuple[int, str]] | None],
                 resume: Callable[[int, str], None]) -> None:
        self._find_orphans, self._resume = find_orphans, resume
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def start(self) -> None:
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._keep_forever, name="recording-keeper", daemon=True)
                self._thread.start()

    def check(self) -> bool:
        """Resumes every orphaned recording now; False once the app is gone."""
        orphans = self._find_orphans()
        for attempt_id, robot_name in orphans or ():
            log.info("attempt %s: its recorder went quiet; recording it here from now on", attempt_id)
            self._resume(attempt_id, robot_name)
        return orphans is not None

    def _keep_forever(self) -> None:
        while True:
            time.sleep(CHECK_S)
            try:
                if not self.check():
                    return
            except Exception as error:  # noqa: BLE001 - the database away for a while: look again later
                log.info("looking for orphaned recordings failed: %s", error)
