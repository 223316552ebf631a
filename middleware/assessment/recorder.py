"""Records what the robot did during an experimental attempt: ground truth and odometry, a few samples a second.

One recorder thread per attempt in progress in this process, reading its own gRPC telemetry stream (the fan-out
hub's messages carry no ground truth). The samples are stored in the attempt every FLUSH_S, with the time, so
another worker can grade an attempt it did not record; when a worker dies mid-attempt, another takes the recording
over once it has been quiet for STALE_S (`RecordingKeeper`), continuing the stored trace. What arrived after the
dead worker's last flush is a gap in the trace, at most FLUSH_S + STALE_S + CHECK_S long.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
import time
from collections.abc import Callable

from middleware.assessment.trace_grading import MAX_TRACE_SAMPLES
from middleware.robots.link import RobotLink, ServerStream
from protos.telelab.v1 import robot_pb2

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
                 initial: list[list[float]] | None = None) -> None:
        self._link, self._flush = link, flush
        self._samples: list[list[float]] = [list(sample) for sample in (initial or [])]
        # A recording taken over goes on from the stored trace's time (the gap while nobody recorded stays a gap).
        self._offset_s = self._samples[-1][0] + 1.0 / RATE_HZ if self._samples else 0.0
        self._lock = threading.Lock()
        self._stream: ServerStream[robot_pb2.Telemetry] | None = None
        self._stopped = threading.Event()
        self._started = time.monotonic()
        self._thread = threading.Thread(target=self._run, name=f"trace-{link.name}", daemon=True)
        self._thread.start()

    def samples(self) -> list[list[float]]:
        """A copy of the samples so far."""
        with self._lock:
            return [list(s) for s in self._samples]

    def stop(self) -> list[list[float]]:
        """Stops recording and returns every sample."""
        self._stopped.set()
        stream = self._stream
        if stream is not None:
            stream.cancel()
        self._thread.join(timeout=3)
        return self.samples()

    def _run(self) -> None:
        last_flush = time.monotonic()
        try:
            self._stream = self._link.stream_telemetry(RATE_HZ)
            for message in self._stream:
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
                    if not self._flush(self.samples()):
                        break  # the attempt ended elsewhere
        except Exception as error:  # a cancelled or broken stream ends the recording
            if not self._stopped.is_set():
                log.warning("trace recording on %s stopped: %s", self._link.name, error)


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
