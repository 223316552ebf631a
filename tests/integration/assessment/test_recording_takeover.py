"""When the worker recording an experimental attempt dies, another takes the recording over from the trace it had
stored; a recorder that is alive is never taken over; and the attempt is graded on the robot's own pose log, the
whole run without the gap the dead worker left, also when the attempt is settled at its deadline."""

from __future__ import annotations

import time
from datetime import UTC, datetime, timedelta

from sqlalchemy import update

from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import drive_for, receive_json


def _experimental_exam(app, course_people) -> int:
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam
    from middleware.db import session_factory
    from middleware.models import User

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        tutor = session.get(User, course_people["tutor1"])
        exam = bank.create_exam(session, tutor, course_people["course"], parse_exam({
            "title": "Drive on", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "task_kind": "reach_point",
            "x_m": 0.0, "y_m": 0.0, "rubric": "0.1:1, 0.5:0.5, 2:0.25", "task_points": 10, "robot_name": "lab-1"}))
        session.commit()
        return exam.id


def _stored_trace(factory, attempt_id: int) -> list:
    from middleware.models.assessment import Attempt

    with factory() as session:
        return list(session.get(Attempt, attempt_id).trace or [])


def _recording_seen(factory, attempt_id: int) -> str:
    """What this process's recorder of the attempt holds and what its row says: whether a recording that stored
    nothing never started, got no telemetry, or flushed into a row it no longer held (seen once under load)."""
    from middleware.assessment import recorder
    from middleware.models.assessment import Attempt

    held = recorder._recorders.get(attempt_id)  # a diagnostic of this process's own recorders
    taken = "no recorder in this process" if held is None else (
        f"a recorder with {len(held.samples())} samples, stopped {held._stopped.is_set()}, "
        f"ended {held._ended.is_set()}, its task done {held._future.done()}")
    with factory() as session:
        row = session.get(Attempt, attempt_id)
        return (f"{taken}; the row: status {row.status}, recorder {row.recorder_key} (this process "
                f"{recorder.process_key()}), heard at {row.recorder_heard_at}, {len(row.trace or [])} samples")


def test_a_recording_whose_worker_died_is_taken_over_and_the_whole_run_is_graded(app, client_as,
                                                                                   course_people) -> None:
    from middleware.assessment import attempts, recorder
    from middleware.assessment.recording import recording_keeper
    from middleware.db import session_factory
    from middleware.models.assessment import Attempt

    exam_id = _experimental_exam(app, course_people)
    student = client_as("student1")
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201, answer
    attempt_id = answer["attempt"]["id"]
    factory = session_factory(app)
    time.sleep(2.5)  # samples for at least one flush
    flushed_by = time.monotonic() + 15  # a loaded machine flushes later, not never
    while not _stored_trace(factory, attempt_id) and time.monotonic() < flushed_by:
        time.sleep(0.2)
    seen = _recording_seen(factory, attempt_id)
    recorder.stop(attempt_id)  # the recording worker dies: its recorder stops, its claim stays behind
    with factory() as session, session.begin():
        died_at = datetime.now(UTC) - timedelta(seconds=recorder.STALE_S + 1)
        session.execute(update(Attempt).where(Attempt.id == attempt_id)
                        .values(recorder_key="dead-host:1", recorder_heard_at=died_at))
        stored = list(session.get(Attempt, attempt_id).trace or [])
    assert stored, f"the first worker had stored samples: {seen}"

    with factory() as session, session.begin():  # a live recorder is never taken over
        assert attempts.claim_recording(session, attempt_id, "someone-else:2", datetime.now(UTC),
                                        died_at - timedelta(seconds=1)) is None
    assert recording_keeper(app).check()  # another worker's keeper, as it runs every few seconds
    drive_for(drive, 1.5, 0.2, 0.0, 1)
    continued_by = time.monotonic() + 15  # as above: the new recorder's flush comes later on a loaded machine
    while True:
        time.sleep(0.5)
        with factory() as session:
            taken = session.get(Attempt, attempt_id)
            assert taken.recorder_key == recorder.process_key()
            trace = list(taken.trace or [])
        if len(trace) > len(stored) + 5 or time.monotonic() > continued_by:
            break
    assert trace[:len(stored)] == stored, "the stored trace is continued, not replaced"
    assert len(trace) > len(stored) + 5 and trace[len(stored)][0] > stored[-1][0], "time goes on after the gap"
    status, answer = api(student, "POST", f"/api/attempts/{attempt_id}/submit")
    drive.close()
    assert status == 200, answer
    with factory() as session:
        graded = session.get(Attempt, attempt_id).trace or []
    assert any(row["item"] == "task" for row in answer["attempt"]["results"])
    gaps = [later[0] - earlier[0] for earlier, later in zip(graded, graded[1:], strict=False)]
    assert graded[0][0] < 0.5 and max(gaps) < 0.5, "graded on the robot's log: the whole run, no gap"
    # one sample fewer at most: the log and the recorder sample 5 Hz on clocks of their own
    assert graded[-1][0] >= trace[-1][0] - 0.5 and len(graded) >= len(trace) - 1


def test_an_attempt_settled_at_its_deadline_is_graded_on_the_robot_s_run_up_to_the_deadline(app, client_as,
                                                                                             course_people) -> None:
    from middleware.assessment import recorder
    from middleware.db import session_factory
    from middleware.models.assessment import Attempt

    exam_id = _experimental_exam(app, course_people)
    student = client_as("student1")
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201, answer
    attempt_id = answer["attempt"]["id"]
    recorder.stop(attempt_id)  # the recording worker dies at once: next to nothing was stored
    drive_for(drive, 1.5, 0.2, 0.0, 1)
    factory = session_factory(app)
    with factory() as session, session.begin():
        attempt = session.get(Attempt, attempt_id)
        stored = len(attempt.trace or [])
        deadline = datetime.now(UTC) - timedelta(seconds=0.5)  # the time ran out while nobody submitted
        attempt.deadline_at = deadline
        started = attempt.started_at.replace(tzinfo=UTC) if attempt.started_at.tzinfo is None else attempt.started_at
    drive.close()
    status, answer = api(student, "GET", f"/api/attempts/{attempt_id}")  # any read settles it
    assert status == 200 and answer["attempt"]["status"] == "submitted", answer
    with factory() as session:
        settled = session.get(Attempt, attempt_id)
        graded = list(settled.trace or [])
        assert settled.submitted_by == "deadline"
    span_s = (deadline - started).total_seconds()
    assert len(graded) > stored and len(graded) >= 4 * span_s - 1, "the robot's 5 Hz log, not the dead one's"
    assert graded[0][0] < 0.5 and abs(graded[-1][0] - span_s) < 0.5, (graded[0][0], graded[-1][0], span_s)
    assert max(later[0] - earlier[0] for earlier, later in zip(graded, graded[1:], strict=False)) < 0.5
