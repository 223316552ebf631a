"""Records what the robot did during an experimental attempt: ground truth and odometry, a few samples a second.

One recorder thread per attempt in progress in this process, reading its own gRPC telemetry stream (the fan-out
hub's messages carry no ground truth). The samples are stored in the attempt every FLUSH_S so another worker can
grade an attempt it did not record; what arrived after the last flush of a worker that died is lost.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from middleware.assessment.trace_grading import MAX_TRACE_SAMPLES
from middleware.robots.link import RobotLink, ServerStream
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
RATE_HZ = 5.0
FLUSH_S = 2.0


class TraceRecorder:
    """Samples [t_s, gx, gy, gth, ox, oy, oth] from the robot's telemetry until stopped."""

    def __init__(self, link: RobotLink, flush: Callable[[list[list[float]]], bool]) -> None:
        self._link, self._flush = link, flush
        self._samples: list[list[float]] = []
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
                sample = [round(time.monotonic() - self._started, 3), round(truth.x_m, 4), round(truth.y_m, 4),
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


def start(attempt_id: int, link: RobotLink, flush: Callable[[list[list[float]]], bool]) -> None:
    """Starts recording for the attempt unless this process records it already."""
    with _recorders_lock:
        if attempt_id not in _recorders:
            _recorders[attempt_id] = TraceRecorder(link, flush)


def stop(attempt_id: int) -> list[list[float]] | None:
    """Stops the attempt's recorder; its samples, or None when this process was not recording it."""
    with _recorders_lock:
        recorder = _recorders.pop(attempt_id, None)
    return recorder.stop() if recorder is not None else None
