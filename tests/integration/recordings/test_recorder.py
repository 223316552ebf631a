"""A session driven on the real lab-1 through the served middleware is recorded to MCAP: read back by the mcap
library with every command in order, each channel's schema, the poses the live stream showed; a cut file reads up
to its last complete chunk; every recording endpoint answers only whom may see it, and hostile ids and ranges are
refused cleanly."""

from __future__ import annotations

import io
import json
import random
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from urllib.error import HTTPError
from urllib.request import Request

import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from sqlalchemy import event

from tests.conftest import LabClient, LiveServer, add_test_account, make_course, make_test_app

ROBOT = "lab-1"
PLAN_TEXT = 'say "recorded"\nwait 0.2s\n'


@pytest.fixture(scope="module")
def recording_lab(tmp_path_factory: pytest.TempPathFactory, skill_server_address: str) -> Iterator[LiveServer]:
    """The served app with recording on (tests keep it off elsewhere), a queue left by a "leave" ending the
    turn, and the accounts the privacy checks need: student2 (another student), tutor1 (teaches student1), tutor2
    (teaches another course), admin1."""
    from middleware.db import session_factory
    from middleware.recordings.parts import recordings_of
    from tests.conftest import _let_go

    tmp_path = tmp_path_factory.mktemp("recordings")
    threads_before = set(threading.enumerate())  # another file's app in this process may still be winding down
    app = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", f"{ROBOT}={skill_server_address}", tmp_path)
    app.config.update(RECORDINGS_ENABLED=True, RECORDINGS_DIR=str(tmp_path / "recordings"))
    with session_factory(app)() as session:
        for name, role in (("student2", "student"), ("tutor1", "tutor"), ("tutor2", "tutor"), ("admin1", "admin")):
            add_test_account(session, name, role)
        session.commit()
    make_course(app, "REC-A", {"student1": "student", "tutor1": "tutor"})
    make_course(app, "REC-B", {"student2": "student", "tutor2": "tutor"})
    app.config["TEST_THREADS_BEFORE"] = threads_before
    app.config["TEST_STATEMENTS"] = statements = set()  # (thread, table) of each statement on a recordings table
    event.listen(session_factory(app).kw["bind"], "before_cursor_execute", lambda _c, _r, sql, *_: statements.update(
        (threading.current_thread().name, table) for table in ("recordings", "recorded_commands") if table in sql))
    server = LiveServer(app)
    try:
        yield server
    finally:
        server.stop()
        recordings_of(app).stop()
        _let_go(app)


def client_for(server: LiveServer, username: str) -> LabClient:
    client = LabClient(server.url)
    client.login(username)
    return client


def get(client: LabClient, path: str) -> tuple[int, bytes]:
    try:
        with client._opener.open(Request(client.base_url + path), timeout=30) as response:
            return response.status, response.read()
    except HTTPError as error:
        return error.code, error.read()


def api_post(client: LabClient, path: str, body: object) -> tuple[int, dict]:
    headers = {"X-CSRFToken": client.csrf_token(f"/lab/{ROBOT}"), "Content-Type": "application/json"}
    request = Request(client.base_url + path, data=json.dumps(body).encode(), method="POST", headers=headers)
    try:
        with client._opener.open(request, timeout=10) as response:
            return response.status, json.loads(response.read())
    except HTTPError as error:
        return error.code, json.loads(error.read())


def receive(ws, kind: str, timeout_s: float = 5.0) -> dict:
    deadline, seen = time.monotonic() + timeout_s, []
    while time.monotonic() < deadline:
        raw = ws.receive(timeout=max(0.05, deadline - time.monotonic()))
        if isinstance(raw, str):
            message = json.loads(raw)
            if message.get("type") == kind:
                return message
            seen.append(message)
    raise AssertionError(f"no {kind} message within {timeout_s} s; got {seen[-3:]}")


def wait_for(condition, timeout_s: float, what: str):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"{what} within {timeout_s} s")


def recording_rows(server: LiveServer) -> list:
    from middleware.db import session_factory
    from middleware.models.recordings import Recording

    with session_factory(server.app)() as session:
        return list(session.query(Recording).order_by(Recording.id))


@pytest.fixture(scope="module")
def driven(recording_lab: LiveServer) -> dict:
    """student1 takes a turn on lab-1, drives 1.5 s at 20 Hz (the live telemetry read meanwhile), starts a skill,
    and leaves; the recording completed. What was sent and seen, and the recording's file."""
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

    student = client_for(recording_lab, "student1")
    telemetry = student.websocket(f"/ws/robots/{ROBOT}/telemetry")  # the console watches before the turn comes
    queue = student.websocket(f"/ws/robots/{ROBOT}/queue")
    queue.send(json.dumps({"type": "join"}))
    wait_for(lambda: receive(queue, "queue", 10).get("is_controller"), 10, "student1 never got the turn")
    wait_for(lambda: any(r.ended_at is None and r.status == "recording" and r.recorder_key
                         for r in recording_rows(recording_lab)), 10, "the turn was never recorded")
    while telemetry.receive(timeout=0) is not None:
        pass  # what it showed before the recording began
    camera = student.websocket(f"/ws/robots/{ROBOT}/camera")  # someone watches the server camera meanwhile
    drive = student.websocket(f"/ws/robots/{ROBOT}/drive")
    receive(drive, "ready")
    sent, live = [], []
    sequence, end = 1, time.monotonic() + 1.5
    while time.monotonic() < end:
        drive.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": 0.2, "angular_radps": 0.3}))
        receive(drive, "ack")
        sent.append(sequence)
        sequence += 1
        while camera.receive(timeout=0) is not None:
            pass
        while (raw := telemetry.receive(timeout=0)) is not None:
            message = json.loads(raw) if isinstance(raw, str) else {}
            if message.get("type") == "telemetry":
                live.append(message)
        time.sleep(0.05)
    status, body = api_post(student, f"/api/robots/{ROBOT}/skills/orientation_control/goals",
                            {"parameters": {"heading_rad": 0.0}, "preempt": True})
    assert status == 202, body
    time.sleep(1.2)  # the goal runs a second: its start and progress are recorded
    goal = body
    status, plan = api_post(student, "/api/plans", {"name": "nudge", "text": PLAN_TEXT})
    assert status == 201, plan
    status, body = api_post(student, f"/api/plans/{plan['plan']['id']}/runs", {"target": ROBOT})
    assert status == 202, body
    time.sleep(0.5)
    drive.close()
    telemetry.close()
    camera.close()
    queue.send(json.dumps({"type": "leave"}))
    queue.close()
    rows = wait_for(lambda: [r for r in recording_rows(recording_lab) if r.status == "ready"], 20,
                    "the recording was never completed after the turn ended")
    root = recordings_of(recording_lab.app).settings.directory
    return {"sent": sent, "live": live, "goal": goal,
            "recording": rows[-1], "parts": files.part_paths(root, rows[-1].id), "student": student}


def test_a_driven_session_reads_back_with_every_command_in_order_each_schema_and_the_live_poses(driven) -> None:
    recording = driven["recording"]
    assert recording.kind == "turn" and recording.end_reason == "turn_ended" and recording.size_bytes > 0
    assert len(driven["parts"]) == 1
    with driven["parts"][0].open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None and summary.statistics.chunk_count >= 2, "flushed in chunks, not at the end"
        schemas = {channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()}
        assert schemas["/odometry"] == "telelab.v1.Odometry" and schemas["/ground_truth"] == "telelab.v1.Pose2D"
        assert schemas["/sonar"] == "telelab.v1.SonarReading" and schemas["/laser"] == "telelab.v1.LaserScan"
        assert schemas["/scene"] == "telelab.v1.SceneDescription" and schemas["/robot_info"] == "telelab.v1.RobotInfo"
        assert schemas["/commands"] == "telelab.recording.v1.CommandRecord"
        assert schemas["/goals"] == "telelab.v1.GoalState"
        assert all(summary.schemas[c.schema_id].encoding == "protobuf" for c in summary.channels.values())
        decoded = list(reader.iter_decoded_messages(log_time_order=True))
    commands = [m for _, c, _, m in decoded if c.topic == "/commands"]
    drives = [c for c in commands if c.action == "drive"]
    assert [c.sequence for c in drives][-len(driven["sent"]):] == driven["sent"] or len(drives) >= len(driven["sent"])
    # The stop sent when the drive socket closes races the queue's "leave" sent just after: when the leave is heard
    # first, that stop is refused (the turn's end stopped the robot already) and recorded so, as it happened.
    if drives and not drives[-1].accepted and drives[-1].outcome == "not_controller":
        assert drives[-1].linear_mps == 0 and drives[-1].angular_radps == 0 and drives[-1].sequence > driven["sent"][-1]
        drives = drives[:-1]
    assert all(c.source == "pad" and c.accepted for c in drives), [
        (c.source, c.accepted, c.outcome) for c in drives if c.source != "pad" or not c.accepted]
    assert [c.sent_unix_s for c in commands] == sorted(c.sent_unix_s for c in commands), "in the order sent"
    assert len({c.sequence for c in drives}) == len(drives), "every command once"
    skill = [c for c in commands if c.action == "activate"]
    assert skill and skill[-1].skill == "orientation_control" and skill[-1].source == "skill_panel"
    assert recording.skill_count == 1
    goals = [m for _, c, _, m in decoded if c.topic == "/goals"]
    assert goals and goals[0].skill == "orientation_control" and skill[-1].outcome == goals[0].goal_id
    assert recording.command_count == len(commands)
    plans = [c for c in commands if c.action == "run_plan"]
    assert [p.plan_name for p in plans] == ["nudge"] and plans[0].source == "plan" and recording.plan_count == 1
    assert recording.source_text == PLAN_TEXT and recording.source_name == "nudge.plan.txt", "the plan that ran"
    # The server camera was watched for about three seconds: its frames are in, thinned to about one a second.
    frames = [(raw.log_time, m) for _, c, raw, m in decoded if c.topic == "/camera"]
    assert 1 <= len(frames) <= 6 and all(m.jpeg[:2] == b"\xff\xd8" for _, m in frames), len(frames)
    gaps = [(b - a) / 1e9 for (a, _), (b, _) in zip(frames, frames[1:], strict=False)]
    assert all(gap >= 0.8 for gap in gaps), gaps
    assert schemas["/camera"] == "telelab.v1.CameraFrame"
    # The recorder reads the robot's one telemetry stream, the viewers' hub: every sample the live viewer was shown
    # within the recording is in the file, at its capture time, with the same pose exactly.
    track = {raw.log_time: m.pose for _, c, raw, m in decoded if c.topic == "/odometry"}
    first, last = min(track), max(track)
    matched = 0
    for message in driven["live"]:
        at, pose = int(message["capture_unix_s"] * 1e9), message["odometry"]["pose"]
        if not first <= at <= last:
            continue
        assert at in track, f"the live sample of {message['capture_unix_s']} is not in the recording"
        recorded = track[at]
        assert (recorded.x_m, recorded.y_m, recorded.theta_rad) == (pose["x_m"], pose["y_m"], pose["theta_rad"])
        matched += 1
    assert matched >= 5, f"only {matched} of {len(driven['live'])} live samples were in the recording"


def test_the_worker_does_none_of_the_recorders_database_work_and_holds_only_its_keepers_thread(
        recording_lab: LiveServer, driven) -> None:
    """The session was found, claimed, heartbeated, its commands logged and copied, and completed, all by the writer
    child: the worker's own engine saw no statement on the recordings' tables from the recorder's threads (the
    keeper's pass, the command log and a recorder pool made them twice a second before; the routes read them, as
    they should), and the keeper's is the recorder's one thread left."""
    statements = recording_lab.app.config["TEST_STATEMENTS"]
    assert driven["recording"].command_count > 0
    from_recorder = sorted(s for s in statements if s[0].startswith(("recordings", "command-log", "recorder-io")))
    assert not from_recorder, f"the recorder's threads used the worker's database: {from_recorder}"
    ours = set(threading.enumerate()) - recording_lab.app.config["TEST_THREADS_BEFORE"]
    held = sorted(t.name for t in ours if t.name.startswith(("recordings", "command-log", "recorder")))
    assert held == ["recordings"], held


def test_a_file_cut_at_a_random_byte_is_read_up_to_its_last_complete_chunk(driven) -> None:
    from middleware.recordings import files

    data = driven["parts"][0].read_bytes()
    whole = [(m.topic, m.log_time_ns, m.data) for m in files.read_part(io.BytesIO(data))]
    assert len(whole) > 50
    counts = []
    for cut in sorted(random.Random(30).sample(range(len(data)), 25)):
        read = [(m.topic, m.log_time_ns, m.data) for m in files.read_part(io.BytesIO(data[:cut]))]
        assert read == whole[:len(read)], f"cut at {cut}: not a prefix of the file's messages"
        counts.append(len(read))
    assert counts == sorted(counts) and counts[-1] > 0
    # The last complete chunk is at most a second of the session: what a crash loses.
    chunk_ends = _chunk_message_counts(data)
    assert max(b - a for a, b in zip([0, *chunk_ends], chunk_ends, strict=False)) < 120


def _chunk_message_counts(data: bytes) -> list[int]:
    from mcap.records import Chunk, Message
    from mcap.stream_reader import StreamReader, breakup_chunk

    total, ends = 0, []
    for record in StreamReader(io.BytesIO(data), emit_chunks=True).records:
        if isinstance(record, Chunk):
            total += sum(isinstance(r, Message) for r in breakup_chunk(record))
            ends.append(total)
    return ends


ENDPOINTS = ("/recordings/{id}", "/api/recordings/{id}", "/api/recordings/{id}/data", "/api/recordings/{id}/camera/0",
             "/api/recordings/{id}/source",
             "/api/recordings/{id}/export.mcap", "/api/recordings/{id}/export/odometry.csv",
             "/api/recordings/{id}/export/commands.csv")


@pytest.mark.parametrize(("username", "sees", "truth"), [
    ("student1", True, False), ("student2", False, False), ("tutor1", True, True), ("tutor2", False, True),
    ("admin1", True, True)])
def test_each_role_sees_only_the_recordings_it_may_and_the_truth_only_where_allowed(
        recording_lab: LiveServer, driven, username: str, sees: bool, truth: bool) -> None:
    recording_id = driven["recording"].id
    client = client_for(recording_lab, username)
    for endpoint in ENDPOINTS:
        status, _ = get(client, endpoint.format(id=recording_id))
        assert status == (200 if sees else 404), (username, endpoint, status)
    status, body = get(client, "/api/recordings")
    listed = [r["id"] for r in json.loads(body)["recordings"]]
    assert (recording_id in listed) == sees
    if not sees:
        return
    status, body = get(client, f"/api/recordings/{recording_id}/data")
    data = json.loads(body)
    assert bool(data["ground_truth"]) == truth and data["truth"] == truth
    assert data["odometry"] and data["commands"] and data["scene"]
    status, jpeg = get(client, f"/api/recordings/{recording_id}/camera/0")
    assert status == 200 and jpeg[:2] == b"\xff\xd8"
    status, _ = get(client, f"/api/recordings/{recording_id}/export/ground_truth.csv")
    assert status == (200 if truth else 404)
    status, body = get(client, f"/api/recordings/{recording_id}/export.mcap")
    topics = {c.topic for c in make_reader(io.BytesIO(body)).get_summary().channels.values()}
    assert ("/ground_truth" in topics) == truth and "/odometry" in topics


def test_anonymous_is_sent_to_log_in_and_the_api_answers_401(recording_lab: LiveServer, driven) -> None:
    anonymous = LabClient(recording_lab.url)
    recording_id = driven["recording"].id
    assert get(anonymous, f"/api/recordings/{recording_id}/data")[0] == 401
    assert get(anonymous, "/api/recordings")[0] == 401
    assert get(anonymous, f"/recordings/{recording_id}")[0] in (302, 401)


@pytest.mark.parametrize(("path", "status", "field"), [
    ("/api/recordings/99999999999999999999999/data", 404, None),
    ("/api/recordings/999999/data", 404, "recording_id"),
    ("/api/recordings/{id}/data?from_s=-1", 400, "from_s"),
    ("/api/recordings/{id}/data?from_s=abc", 400, "from_s"),
    ("/api/recordings/{id}/data?to_s=NaN", 400, "to_s"),
    ("/api/recordings/{id}/data?from_s=5&to_s=1", 400, "to_s"),
    ("/api/recordings/{id}/data?to_s=1e400", 400, "to_s"),
    ("/api/recordings/{id}/export/passwords.csv", 404, "channel"),
    ("/api/recordings/{id}/export/ground_truth.csv", 404, "channel"),
    ("/api/recordings/{id}/camera/999999", 404, "index"),
    ("/api/recordings/of/turn/0", 404, "ref_id"),
    ("/api/recordings/of/%00/1", 400, None),
])
def test_hostile_ids_and_ranges_are_refused_naming_the_field(
        recording_lab: LiveServer, driven, path: str, status: int, field: str | None) -> None:
    client = client_for(recording_lab, "student1")
    got, body = get(client, path.format(id=driven["recording"].id))
    assert got == status, (path, got, body[:300])
    if field is not None:
        assert json.loads(body)["error"]["field"] == field


def test_deleting_an_account_deletes_its_recordings_and_their_files(recording_lab: LiveServer, driven) -> None:
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

    app = recording_lab.app
    root: Path = recordings_of(app).settings.directory
    recording_id = driven["recording"].id
    with session_factory(app)() as session:
        session.delete(session.query(User).filter_by(username="student1").one())
        session.commit()
    recordings_of(app).keeper.sweep()
    assert not [r for r in recording_rows(recording_lab) if r.id == recording_id]
    assert not files.part_paths(root, recording_id)
