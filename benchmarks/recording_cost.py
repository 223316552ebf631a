"""What recording every session costs the live path (issue 30): drive -> ack and telemetry -> viewer latency with
the recorder off and on, in one run, on the same lab; the bytes a minute of session takes; and the replay data's
answer time for a 30-minute recording.

Run `python -m benchmarks.recording_cost [--quick] [--output DIR]`: prints a table, writes DIR/recording_cost.json.
The blocks alternate off, on, off, on (the recorder's observer switched, the elected keeper recording lab-1's turn
while on), so both see the machine in the same state; the ratio of the on p50 to the off p50 is graded <= 1.05.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from benchmarks.lab_under_test import Browser, LabUnderTest
from benchmarks.latency import measure_drive, take_control
from benchmarks.report import Measurement, percentile_ms, print_table, write_json

RATIO_TARGET = 1.05


def measure_telemetry(browser: Browser, duration_s: float) -> list[float]:
    """capture -> delivered latency [s] of every telemetry message a viewer socket receives."""
    socket = browser.websocket("/ws/robots/lab-1/telemetry")
    samples, end = [], time.monotonic() + duration_s
    while time.monotonic() < end:
        raw = socket.receive(timeout=1)
        if isinstance(raw, str):
            message = json.loads(raw)
            if message.get("type") == "telemetry":
                samples.append(time.time() - float(message["capture_unix_s"]))
    socket.close()
    return samples


def replay_answer_s(lab: LabUnderTest, browser: Browser, minutes: float) -> tuple[float, float]:
    """Seconds the replay data of a synthetic recording of `minutes` (10 Hz, every channel) takes to answer: its
    first 30 s (the page's first frame waits for these) and the whole."""
    from datetime import UTC, datetime

    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.recordings import Recording
    from middleware.recordings import channels, files, recordings_of
    from protos.telelab.v1 import robot_pb2

    with session_factory(lab.app)() as session:
        user = session.query(User).filter_by(username=lab.usernames[0]).one()
        row = Recording(user_id=user.id, robot_name="lab-1", kind="turn", explicit=True, status="ready",
                        started_at=datetime.now(UTC), ended_at=datetime.now(UTC), end_reason="bench")
        session.add(row)
        session.commit()
        recording_id = row.id
    writer = files.PartWriter(files.new_part_path(recordings_of(lab.app).settings.directory, recording_id, "bench"),
                              {"robot": "lab-1"})
    start = time.time()
    for i in range(int(minutes * 60 * 10)):
        at = int((start + i / 10) * 1e9)
        writer.write(channels.ODOMETRY, robot_pb2.Odometry(pose=robot_pb2.Pose2D(x_m=i * 1e-3)), at)
        writer.write(channels.GROUND_TRUTH, robot_pb2.Pose2D(x_m=i * 1e-3), at)
        writer.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=[1.0] * 8), at)
        writer.write(channels.LASER, robot_pb2.LaserScan(ranges_m=[2.0] * 90), at)
    writer.finish()
    started = time.perf_counter()
    status, _ = browser.get(f"/api/recordings/{recording_id}/data?to_s=30")  # what the page asks first
    if status != 200:
        raise RuntimeError(f"replay data answered {status}")
    first_s = time.perf_counter() - started
    started = time.perf_counter()
    status, _ = browser.get(f"/api/recordings/{recording_id}/data")  # the whole, loaded behind the first frame
    return first_s, time.perf_counter() - started if status == 200 else float("nan")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    args = parser.parse_args(argv)
    from middleware.recordings import recordings_of

    lab = LabUnderTest(users=1)
    rows: list[Measurement] = []
    try:
        recordings = recordings_of(lab.app)
        recordings._active = False  # noqa: SLF001 - the benchmark switches the recorder between blocks
        browser = lab.browser(0)
        queue = take_control(browser)
        drives, views = {"off": [], "on": []}, {"off": [], "on": []}
        count, window_s = (40, 2.0) if args.quick else (300, 8.0)
        for block in ("off", "on", "off", "on"):
            recordings._active = block == "on"  # noqa: SLF001
            if block == "on":
                recordings.keeper.start()
                time.sleep(2.0)  # the keeper opens the turn's recording and its recorder starts
            drives[block] += measure_drive(browser, count)
            views[block] += measure_telemetry(browser, window_s)
        time.sleep(2.0 if args.quick else 20.0)
        queue.send(json.dumps({"type": "leave"}))
        queue.close()
        time.sleep(3.0)
        from middleware.db import session_factory
        from middleware.models.recordings import Recording

        with session_factory(lab.app)() as session:
            recorded = session.query(Recording).filter(Recording.status == "ready").all()
            minutes = sum(((r.ended_at - r.started_at).total_seconds() for r in recorded), 0.0) / 60
            size = sum(r.size_bytes for r in recorded)
        for name, samples in (("drive -> ack", drives), ("telemetry -> viewer", views)):
            off, on = percentile_ms(samples["off"], 50), percentile_ms(samples["on"], 50)
            ratio = on / off if off else None
            rows += [Measurement(f"{name}, recording on", "p50", on, "ms", "", off, None),
                     Measurement(f"{name}, recording on", "p99", percentile_ms(samples["on"], 99), "ms", "",
                                 percentile_ms(samples["off"], 99), None),
                     Measurement(f"{name}", "p50 on / p50 off", ratio, "x", f"<= {RATIO_TARGET}", None,
                                 None if args.quick or ratio is None else ratio <= RATIO_TARGET)]
        rows.append(Measurement("recording size", "bytes per minute of session",
                                size / minutes if minutes else None, "B/min", "", None, None))
        first_s, whole_s = replay_answer_s(lab, browser, 3.0 if args.quick else 30.0)
        label = "replay data, 3 min" if args.quick else "replay data, 30 min"
        rows += [Measurement(label, "first 30 s (the first frame's data)", first_s * 1000, "ms", "", None, None),
                 Measurement(label, "the whole (loaded behind it)", whole_s * 1000, "ms", "", None, None)]
        recordings.stop()
    finally:
        lab.stop()
    print_table("Recording cost on the live path", rows)
    write_json(args.output / "recording_cost.json", rows, {"drive_off_median_ms": statistics.median(
        drives["off"]) * 1000 if drives["off"] else None})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
