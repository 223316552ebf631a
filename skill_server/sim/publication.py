"""Where the world's loop publishes snapshots and frames, and where other threads wait for them."""

from __future__ import annotations

import itertools
import threading

from skill_server.sim.camera import MAX_CAMERA_FPS
from skill_server.sim.snapshots import CameraFrame, RobotSnapshot


class Publication:
    """Latest snapshot and frame behind conditions, plus the camera demand of the viewers.

    Readers never see a half-built record: the loop swaps in a whole frozen object under the lock.
    """

    def __init__(self) -> None:
        self._snapshot: RobotSnapshot | None = None
        self._frame: CameraFrame | None = None
        self._snapshot_changed = threading.Condition()
        self._frame_changed = threading.Condition()
        self._closed = False
        self._camera_lock = threading.Lock()
        self._camera_fps_by_subscriber: dict[int, float] = {}
        self._subscriber_ids = itertools.count(1)

    @property
    def snapshot(self) -> RobotSnapshot:
        """The latest snapshot (the world publishes one before anyone can ask)."""
        assert self._snapshot is not None
        return self._snapshot

    @property
    def frame(self) -> CameraFrame | None:
        """The latest frame, if any was rendered."""
        return self._frame

    def publish_snapshot(self, snapshot: RobotSnapshot) -> None:
        """Replaces the snapshot and wakes its readers (the loop calls this)."""
        with self._snapshot_changed:
            self._snapshot = snapshot
            self._snapshot_changed.notify_all()

    def publish_frame(self, frame: CameraFrame) -> None:
        """Replaces the frame and wakes its readers (the loop calls this)."""
        with self._frame_changed:
            self._frame = frame
            self._frame_changed.notify_all()

    def close(self) -> None:
        """Makes every present and future wait return None at once."""
        self._closed = True
        self.wake_waiters()

    def wake_waiters(self) -> None:
        """Wakes every blocked reader so it can re-check its cancel flag."""
        for condition in (self._snapshot_changed, self._frame_changed):
            with condition:
                condition.notify_all()

    def wait_for_snapshot(
        self, after_tick: int, timeout_s: float, cancelled: threading.Event | None = None
    ) -> RobotSnapshot | None:
        """The newest snapshot with a tick above after_tick; None on timeout, cancel or close."""

        def newer(snapshot: RobotSnapshot | None) -> bool:
            return snapshot is not None and snapshot.tick > after_tick

        def ready() -> bool:
            return newer(self._snapshot) or self._closed or bool(cancelled and cancelled.is_set())

        with self._snapshot_changed:
            self._snapshot_changed.wait_for(ready, timeout_s)
        snapshot = self._snapshot
        return snapshot if newer(snapshot) and not self._closed else None

    def wait_for_frame(
        self, after_sequence: int, timeout_s: float, cancelled: threading.Event | None = None
    ) -> CameraFrame | None:
        """The newest frame with a sequence above after_sequence; None on timeout, cancel or close."""

        def newer(frame: CameraFrame | None) -> bool:
            return frame is not None and frame.frame_sequence > after_sequence

        def ready() -> bool:
            return newer(self._frame) or self._closed or bool(cancelled and cancelled.is_set())

        with self._frame_changed:
            self._frame_changed.wait_for(ready, timeout_s)
        frame = self._frame
        return frame if newer(frame) and not self._closed else None

    def subscribe_camera(self, max_fps: float) -> CameraSubscription:
        """Registers a viewer; the loop renders at the highest fps any viewer asked for (capped)."""
        subscriber_id = next(self._subscriber_ids)
        with self._camera_lock:
            self._camera_fps_by_subscriber[subscriber_id] = min(float(max_fps), MAX_CAMERA_FPS)
        return CameraSubscription(self, subscriber_id)

    def unsubscribe_camera(self, subscriber_id: int) -> None:
        """Withdraws a viewer's request."""
        with self._camera_lock:
            self._camera_fps_by_subscriber.pop(subscriber_id, None)

    @property
    def camera_subscriber_count(self) -> int:
        """How many viewers hold the camera on."""
        with self._camera_lock:
            return len(self._camera_fps_by_subscriber)

    @property
    def requested_camera_fps(self) -> float:
        """The rate the loop should render at; 0 when nobody watches."""
        with self._camera_lock:
            return max(self._camera_fps_by_subscriber.values(), default=0.0)


class CameraSubscription:
    """A viewer's claim on the camera; close it (or leave the with-block) to let rendering stop."""

    def __init__(self, publication: Publication, subscriber_id: int) -> None:
        self._publication = publication
        self._subscriber_id = subscriber_id

    def close(self) -> None:
        """Withdraws this viewer's request."""
        self._publication.unsubscribe_camera(self._subscriber_id)

    def __enter__(self) -> CameraSubscription:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
