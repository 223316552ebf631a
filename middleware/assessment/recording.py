"""The recording of an experimental attempt's run, from its start to its end: the claim (one process of the cluster
records an attempt), the recorder's flushes (sessions of their own: it runs after the request, as a task on the
channel loop, its flushes on the loop's shared pool), the keeper that takes over a recording whose process went
quiet, and the run read back from the robot's own pose log when the attempt is submitted."""

from __future__ import annotations

import weakref
from datetime import UTC, datetime, timedelta

from flask import Flask, current_app, has_app_context

from middleware.assessment import attempts, recorder
from middleware.assessment.policy import get_attempt, get_exam
from middleware.db import after_commit, get_session, session_factory
from middleware.models.accounts import as_utc
from middleware.models.assessment import Attempt, Exam
from middleware.robots.link import RobotUnavailable
from middleware.robots.registry import robot_registry

_KEEPER_KEY = "telelab.recording_keeper"


def start_recording(attempt_id: int, robot_name: str) -> None:
    """Records the robot's ground truth for the attempt in this process, flushing to the database, unless another
    process records it (a recording that went quiet is taken over, after the trace stored so far)."""
    link = robot_registry().get(robot_name)
    if link is None:
        return
    factory = session_factory(current_app._get_current_object())  # type: ignore[attr-defined]
    key, now = recorder.process_key(), datetime.now(UTC)
    with factory() as session, session.begin():
        stored = attempts.claim_recording(session, attempt_id, key, now, now - timedelta(seconds=recorder.STALE_S))
    if stored is None:
        return

    def flush(trace: list[list[float]]) -> bool:
        with factory() as session, session.begin():
            return attempts.record_trace(session, attempt_id, trace, key, datetime.now(UTC))

    recorder.start(attempt_id, link, flush, stored)
    recording_keeper(current_app._get_current_object()).start()  # type: ignore[attr-defined]


def recording_keeper(app: Flask) -> recorder.RecordingKeeper:
    """The app's keeper of orphaned recordings (made once)."""
    keeper = app.extensions.get(_KEEPER_KEY)
    if keeper is None:
        factory = session_factory(app)
        app_ref = weakref.ref(app)  # the keeper's thread ends with the app (tests make many)

        def find_orphans() -> list[tuple[int, str]] | None:
            if app_ref() is None:
                return None
            with factory() as session:
                return attempts.orphaned_recordings(session, datetime.now(UTC) - timedelta(seconds=recorder.STALE_S))

        def resume(attempt_id: int, robot_name: str) -> None:
            alive = app_ref()
            if alive is not None:
                with alive.app_context():
                    start_recording(attempt_id, robot_name)

        keeper = app.extensions.setdefault(_KEEPER_KEY, recorder.RecordingKeeper(find_orphans, resume))
    return keeper


def record_after_commit(attempt: Attempt, exam: Exam) -> None:
    """For an experimental test, starts recording the attempt's robot once the attempt is committed (the recorder
    writes the trace into the attempt's row from the loop's shared pool)."""
    robot_name, attempt_id = attempt.robot_name or exam.robot_name, attempt.id
    if exam.kind == "experimental" and robot_name:
        after_commit(lambda: start_recording(attempt_id, robot_name))


def finish_recording(attempt_id: int) -> list[list[float]] | None:
    """The attempt's run: from the robot's own pose log when it covers the whole attempt (complete, whichever worker
    recorded and whether it lived), else what this process recorded; None: grade what was stored."""
    recorded = recorder.stop(attempt_id)
    session = get_session()
    attempt = get_attempt(session, attempt_id)
    exam = get_exam(session, attempt.exam_id)
    robot_name = attempt.robot_name or exam.robot_name
    if exam.kind == "experimental" and robot_name:
        kept = robot_run(robot_name, as_utc(attempt.started_at), datetime.now(UTC))
        if kept is not None:
            return kept
    return recorded


def robot_run(robot_name: str, since: datetime, until: datetime) -> list[list[float]] | None:
    """[t_s, gx, gy, gth, ox, oy, oth] from the robot's pose log between since and until; None when the robot does
    not answer, no longer keeps that time (it restarted since), or there is no app to ask it through."""
    if not has_app_context():
        return None
    link = robot_registry().get(robot_name)
    if link is None:
        return None
    since_unix_s = since.timestamp()
    try:
        log = link.pose_log(since_unix_s, until.timestamp())
    except RobotUnavailable:
        return None
    if not log.oldest_unix_s or log.oldest_unix_s > since_unix_s + 2.0 / recorder.RATE_HZ:
        return None
    return [[round(s.unix_s - since_unix_s, 3), round(s.ground_truth.x_m, 4), round(s.ground_truth.y_m, 4),
             round(s.ground_truth.theta_rad, 4), round(s.odometry.x_m, 4), round(s.odometry.y_m, 4),
             round(s.odometry.theta_rad, 4)] for s in log.samples]
