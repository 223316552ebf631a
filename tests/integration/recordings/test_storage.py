"""The recordings' storage rules: which recordings go first past the retention and the disk limits, and a session
whose recorder stopped (its process died, the election moved) continued by another recorder in a new part, read
back and exported as one file."""

from __future__ import annotations

import io
import time
from datetime import timedelta

from mcap.reader import make_reader

from tests.conftest import add_test_account, make_course

MB = 1024 * 1024


def test_past_the_limits_the_oldest_go_first_and_people_in_no_course_before_the_others(app) -> None:
    from middleware.db import session_factory
    from middleware.models.accounts import utc_now
    from middleware.models.recordings import Recording
    from middleware.recordings import services

    now = utc_now()
    with session_factory(app)() as session:
        enrolled = add_test_account(session, "enrolled", "student")
        left = add_test_account(session, "left", "student")
        heavy = add_test_account(session, "heavy", "student")
        session.commit()
        ids = {}

        def add(name: str, user, days_ago: float, mb: int, ended: bool = True) -> None:
            row = Recording(user_id=user.id, robot_name="lab-1", kind="turn", explicit=False, status="ready",
                            started_at=now - timedelta(days=days_ago),
                            ended_at=now - timedelta(days=days_ago) + timedelta(minutes=5) if ended else None,
                            size_bytes=mb * MB)
            session.add(row)
            session.flush()
            ids[row.id] = name

        add("ancient", enrolled, 400, 1)
        add("enrolled-old", enrolled, 30, 10)
        add("left-new", left, 2, 10)
        add("heavy-1", heavy, 20, 30)
        add("heavy-2", heavy, 10, 30)
        add("enrolled-new", enrolled, 1, 10)
        add("open-now", enrolled, 0, 10, ended=False)
        session.commit()
    make_course(app, "KEEP", {"enrolled": "student", "heavy": "student"})
    with session_factory(app)() as session:
        doomed = services.removal_order(session, max_total_bytes=40 * MB, max_user_bytes=40 * MB,
                                        retention_days=365, now=now)
    # By hand: "ancient" is past the retention. Left 100 MB, heavy's 60 over their 40: their oldest goes (70 MB).
    # Over the total of 40: first those in no course ("left-new": 60), then the oldest ("enrolled-old": 50,
    # "heavy-2": 20). The open session counts in the total but is never removed.
    assert [ids[i] for i in doomed] == ["ancient", "heavy-1", "left-new", "enrolled-old", "heavy-2"], [
        ids[i] for i in doomed]
    assert "open-now" not in [ids[i] for i in doomed], "a session being recorded is never removed"


def wait_for(condition, timeout_s: float, what: str):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if value := condition():
            return value
        time.sleep(0.1)
    raise AssertionError(f"{what} within {timeout_s} s")


def test_a_session_whose_recorder_stopped_goes_on_in_a_new_part_and_exports_as_one_file(app, tmp_path) -> None:
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.recordings import Recording
    from middleware.recordings import export, files, services
    from middleware.recordings.parts import recordings_of
    from middleware.recordings.recorder import RecordingKeeper
    from middleware.robots.registry import robot_registry

    app.config.update(RECORDINGS_ENABLED=True, RECORDINGS_DIR=str(tmp_path / "recordings"))
    sessions = session_factory(app)
    with sessions() as session, session.begin():
        student = session.query(User).filter_by(username="student1").one()
        recording = services.start_recording(session, student.id, "lab-1", "exercise_run", ref_id=7,
                                             source_text="robot.drive(0.1, 0)\n", source_name="square.py")
        recording_id = recording.id
    first = recordings_of(app).keeper
    first.check()  # nobody watches lab-1: the elected worker records it, after SOLO_AFTER_S for a watching one
    wait_for(lambda: first.recording_now() == [recording_id], 10, "the session was never recorded")
    time.sleep(2.5)
    first.stop()  # as if its process died: the part is left as flushed, the row still open
    second = RecordingKeeper(app, sessions, robot_registry(app), first.settings)
    try:
        second.check()
        assert second.recording_now() == [recording_id], "the open session was taken over"
        time.sleep(2.0)
        with sessions() as session, session.begin():
            assert services.stop_recording(session, recording_id, "exercise_submitted")
        row = wait_for(lambda: (r := sessions().get(Recording, recording_id)) and r.status == "ready" and r, 10,
                       "the taken-over recording was never completed")
    finally:
        second.stop()
    assert row.end_reason == "exercise_submitted" and row.kind == "exercise_run" and row.ref_id == 7
    root = first.settings.directory
    parts = files.part_paths(root, recording_id)
    assert len(parts) == 2, parts
    per_part = [[m.log_time_ns for m in files.read_part(p) if m.topic == "/odometry"] for p in parts]
    # The second part goes on where the first stopped (a new stream starts with the latest reading, which the first
    # may have written too: read back once).
    assert per_part[0] and per_part[1] and max(per_part[0]) <= min(per_part[1])
    messages = files.read_recording(root, recording_id)
    odometry = [m.log_time_ns for m in messages if m.topic == "/odometry"]
    assert odometry == sorted(set(per_part[0]) | set(per_part[1])), "every sample once, in order"
    merged = export.merged_mcap(messages, {"recording_id": str(recording_id)})
    summary = make_reader(io.BytesIO(merged)).get_summary()
    assert summary is not None and summary.statistics.message_count == len(messages)
    assert row.size_bytes == sum(p.stat().st_size for p in parts)
