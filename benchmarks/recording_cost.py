"""What recording every session costs (issue 30), each figure beside a floor measured in the same run:

- the live path: drive -> ack and telemetry -> viewer latency with the recorder off and on, in blocks that
  alternate off/on, on/off, ... (so both see the machine in the same state; the machine is shared), each pair
  giving a ratio of the on p50 to the off p50. The figure is the median of the pairs' ratios (graded <= 1.05), the
  spread is their range; the floor of each latency is the off blocks' own. During every block a console watches
  the robot's telemetry (its socket is the telemetry -> viewer sample) while the drive pad sends, as in a session.
  "Off" is the keeper paused (no recorder, no command notes), "on" the elected keeper recording lab-1's turn.
- bytes per minute of session: one part recorded while driving with the console open, against the floor of its
  messages' own bytes (serialized, before MCAP's framing and zstd).
- the replay page's time to first frame for a 30-minute recording (10 Hz odometry, truth, sonar and laser with
  lab-1's sensor counts, a command a second; written synthetically through the recorder's own `files.PartWriter`,
  a chunk a second as the recorder closes them), in headless Chromium: from the navigation's start to the browser
  frame after the page marks its first frame, against the floor of the same page on a 10-second recording; and
  the time until the whole recording is loaded behind it.

Run `python -m benchmarks.recording_cost [--quick] [--output DIR]`: prints a table, writes DIR/recording_cost.json.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import statistics
import threading
import time
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

from benchmarks.lab_under_test import PASSWORD, Browser, LabUnderTest
from benchmarks.latency import measure_drive, take_control
from benchmarks.report import Measurement, percentile_ms, print_table, write_json

RATIO_TARGET = 1.05
SETTLE_ON_S = 2.0  # the keeper's pass, the recorder's subscription and its first second on the pool
SETTLE_OFF_S = 1.0
REPLAY_LOADS = 3  # page loads of each recording, alternated: the median counts

# Each frame the page marks: performance.now() (from the navigation's start) at the browser frame after the mark.
MARK_TIMES = """
window.__replayTimes = {};
new MutationObserver((records) => {
  for (const record of records) {
    const name = record.attributeName;
    if (name in window.__replayTimes) continue;
    window.__replayTimes[name] = null;
    requestAnimationFrame(() => { window.__replayTimes[name] = performance.now(); });
  }
}).observe(document, { attributes: true, subtree: true, attributeFilter: ["data-first-frame", "data-ready"] });
"""


class TelemetryViewer:
    """A console's telemetry socket read on a thread of the client: capture -> delivered latency of each message."""

    def __init__(self, browser: Browser) -> None:
        self._socket = browser.websocket("/ws/robots/lab-1/telemetry")
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._samples: list[float] = []
        self._thread = threading.Thread(target=self._read, name="bench-viewer", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            raw = self._socket.receive(timeout=0.5)
            if isinstance(raw, str):
                message = json.loads(raw)
                if message.get("type") == "telemetry":
                    with self._lock:
                        self._samples.append(time.time() - float(message["capture_unix_s"]))

    def take(self) -> list[float]:
        """The samples since the last take."""
        with self._lock:
            samples, self._samples = self._samples, []
        return samples

    def close(self) -> None:
        self._stop.set()
        self._thread.join(3)
        self._socket.close()


def switch(lab: LabUnderTest, on: bool) -> None:
    """The recorder on (the keeper records the turn, commands are noted) or off (paused: nothing recorded)."""
    from middleware.recordings import recordings_of

    recordings = recordings_of(lab.app)
    recordings._active = on  # noqa: SLF001 - the command path's observer notes commands only while on
    recordings.keeper.pause(not on)  # the keeper's thread (a pass every CHECK_S) applies it
    deadline = time.monotonic() + 15
    while bool(recordings.keeper.recording_now()) != on:
        if time.monotonic() > deadline:
            raise RuntimeError(f"the recorder did not turn {'on' if on else 'off'}")
        time.sleep(0.05)
    time.sleep(SETTLE_ON_S if on else SETTLE_OFF_S)


def live_path(lab: LabUnderTest, browser: Browser, pairs: int, drives: int) -> dict[str, Any]:
    """Alternating off/on blocks; every block's drive and viewer samples, and the process's CPU seconds a second
    (middleware, recorder and client alike: only the recorder differs between the blocks)."""
    blocks: list[tuple[str, list[float], list[float]]] = []
    cpu: list[tuple[str, float]] = []
    viewer = TelemetryViewer(browser)
    try:
        for pair in range(pairs):
            for state in (("off", "on") if pair % 2 == 0 else ("on", "off")):
                switch(lab, state == "on")
                viewer.take()
                cpu_started, started = time.process_time(), time.monotonic()
                drive = measure_drive(browser, drives)
                cpu.append((state, (time.process_time() - cpu_started) / (time.monotonic() - started)))
                blocks.append((state, drive, viewer.take()))
    finally:
        viewer.close()
    return {"blocks": blocks, "cpu": cpu}


def cpu_rows(cpu: list[tuple[str, float]]) -> list[Measurement]:
    """The process's CPU while recording, beside its CPU with the recorder off (a load on the machine slows a
    block, but does not add CPU seconds to this process: steadier than the latencies on a shared machine)."""
    on = [share for state, share in cpu if state == "on"]
    off = [share for state, share in cpu if state == "off"]
    if not on or not off:
        return []
    on_ms, off_ms = statistics.median(on) * 1000, statistics.median(off) * 1000
    return [Measurement("process CPU, recording on", "CPU a second (median of blocks)", on_ms, "ms/s", "-", off_ms,
                        None, f"recording adds {on_ms - off_ms:.1f} ms/s"),
            Measurement("process CPU", "on / off", on_ms / off_ms, "x", "-", 1.0, None)]


def ratio_rows(name: str, blocks: list[tuple[str, list[float]]], quick: bool) -> list[Measurement]:
    """The pooled p50/p99 on beside off, and the median and range of the pairs' p50 ratios."""
    on = [s for state, samples in blocks if state == "on" for s in samples]
    off = [s for state, samples in blocks if state == "off" for s in samples]
    ratios = []
    for index in range(0, len(blocks) - 1, 2):
        pair = dict(blocks[index:index + 2])
        if pair.get("on") and pair.get("off"):
            ratios.append(percentile_ms(pair["on"], 50) / percentile_ms(pair["off"], 50))
    median = statistics.median(ratios) if ratios else None
    spread = f"{len(ratios)} pairs: {min(ratios):.3f}-{max(ratios):.3f}" if ratios else "no pairs"
    return [
        Measurement(f"{name}, recording on", "p50", percentile_ms(on, 50), "ms", "-", percentile_ms(off, 50)),
        Measurement(f"{name}, recording on", "p99", percentile_ms(on, 99), "ms", "-", percentile_ms(off, 99)),
        Measurement(name, "p50 on / p50 off, median of pairs", median, "x", f"<= {RATIO_TARGET}", 1.0,
                    None if quick or median is None else median <= RATIO_TARGET, spread),
    ]


def bytes_window(lab: LabUnderTest, browser: Browser, window_s: float) -> tuple[float, float, float]:
    """One part recorded over window_s of driving with the console open, completed: (bytes a minute on disk,
    the messages' own bytes a minute, the part's seconds)."""
    from middleware.recordings import files, recordings_of

    switch(lab, True)
    viewer = TelemetryViewer(browser)
    drive = browser.websocket("/ws/robots/lab-1/drive")
    json.loads(drive.receive(timeout=10))
    end, sequence = time.monotonic() + window_s, 10_000
    while time.monotonic() < end:
        sequence += 1
        drive.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": 0.0, "angular_radps": 0.2}))
        drive.receive(timeout=5)
        time.sleep(0.1)  # the pad's 10 commands a second
    drive.close()
    viewer.close()
    recordings = recordings_of(lab.app)
    recording_id = recordings.keeper.recording_now()[0]
    switch(lab, False)  # the part is closed (chunks written), its recorder gone
    part = files.part_paths(recordings.settings.directory, recording_id)[-1]
    messages = list(files.read_part(part))
    times = [m.log_time_ns for m in messages if m.topic == "/odometry"]
    seconds = (max(times) - min(times)) / 1e9
    minutes = seconds / 60
    return part.stat().st_size / minutes, sum(len(m.data) for m in messages) / minutes, seconds


def synthetic_recording(lab: LabUnderTest, seconds: float) -> int:
    """A ready recording of bench0 on lab-1, `seconds` long, written through the recorder's writer; its id."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.recordings import Recording
    from middleware.recordings import channels, files, recordings_of
    from middleware.robots.registry import robot_registry
    from protos.telelab.v1 import robot_pb2

    link = robot_registry(lab.app).get("lab-1")
    info, scene = link.info(), link.scene(max_age_s=60.0)
    sonars, beams = len(info.sonars) or 16, info.laser.beam_count or 181
    start = time.time() - seconds - 60
    with session_factory(lab.app)() as session:
        user = session.query(User).filter_by(username=lab.usernames[0]).one()
        row = Recording(user_id=user.id, robot_name="lab-1", kind="turn", explicit=True, status="ready",
                        started_at=datetime.fromtimestamp(start, UTC),
                        ended_at=datetime.fromtimestamp(start, UTC) + timedelta(seconds=seconds), end_reason="bench",
                        command_count=int(seconds))
        session.add(row)
        session.commit()
        recording_id = row.id
    buffer = io.BytesIO()  # the recorder's chunks, a second each, without an fsync a second
    writer = files.PartWriter(buffer, {"robot": "lab-1", "kind": "turn"})
    writer.write(channels.ROBOT_INFO, info, int(start * 1e9))
    writer.write(channels.SCENE, scene, int(start * 1e9))
    for i in range(int(seconds * 10) + 1):
        t = start + i / 10
        at = int(t * 1e9)
        pose = robot_pb2.Pose2D(x_m=0.5 * (i % 600) / 60, y_m=0.2 * ((i // 600) % 10), theta_rad=0.001 * (i % 3000))
        writer.write(channels.ODOMETRY, robot_pb2.Odometry(pose=pose, linear_mps=0.2, angular_radps=0.1), at)
        writer.write(channels.GROUND_TRUTH, pose, at)
        writer.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=[1.0 + 0.01 * ((i + k) % 90)
                                                                      for k in range(sonars)]), at)
        writer.write(channels.LASER, robot_pb2.LaserScan(angle_min_rad=-1.57, angle_increment_rad=3.14 / beams,
                                                         ranges_m=[2.0 + 0.001 * ((i * 7 + k) % 500)
                                                                   for k in range(beams)]), at)
        if i % 10 == 0:
            writer.write(channels.COMMANDS, channels.CommandRecord(
                sent_unix_s=t, sequence=i // 10 + 1, source="pad", action="drive", linear_mps=0.2,
                angular_radps=0.1, accepted=True), at)
            writer.flush()
    writer.finish()
    path = files.new_part_path(recordings_of(lab.app).settings.directory, recording_id, "bench")
    path.write_bytes(buffer.getvalue())
    return recording_id


def replay_times(lab: LabUnderTest, long_id: int, short_id: int, loads: int) -> dict[str, dict[str, list[float]]]:
    """In headless Chromium, logged in as bench0: each recording's page loaded `loads` times, alternated;
    {long|short: {first_frame|ready: [ms from the navigation's start]}}."""
    from playwright.sync_api import sync_playwright

    from benchmarks.feedback import CHROMIUM_ARGS, CHROMIUM_PATH

    times: dict[str, dict[str, list[float]]] = {name: {"first_frame": [], "ready": []} for name in ("long", "short")}
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM_PATH, args=CHROMIUM_ARGS)
        try:
            context = chromium.new_context(viewport={"width": 1280, "height": 800})
            context.add_init_script(MARK_TIMES)
            page = context.new_page()
            page.goto(f"{lab.middleware.url}/login")
            page.fill("#username", lab.usernames[0])
            page.fill("#password", PASSWORD)
            page.get_by_role("button", name="Log in").click()
            page.locator('[data-field="username"]').first.wait_for(state="attached")
            for _ in range(loads):
                for name, recording_id in (("long", long_id), ("short", short_id)):
                    page.goto(f"{lab.middleware.url}/recordings/{recording_id}", wait_until="commit")
                    page.locator('#replay[data-ready="true"]').wait_for(state="attached", timeout=120_000)
                    page.wait_for_function("() => window.__replayTimes['data-ready'] != null", timeout=10_000)
                    marks = page.evaluate("() => window.__replayTimes")
                    times[name]["first_frame"].append(float(marks["data-first-frame"]))
                    times[name]["ready"].append(float(marks["data-ready"]))
        finally:
            chromium.close()
    return times


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    args = parser.parse_args(argv)
    from middleware.recordings import recordings_of

    pairs, drives, window_s, minutes = (2, 40, 15.0, 3.0) if args.quick else (12, 150, 60.0, 30.0)
    lab = LabUnderTest(users=1)
    rows: list[Measurement] = []
    extra: dict[str, Any] = {"quick": args.quick, "load_average_at_start": os.getloadavg(), "cores": os.cpu_count()}
    try:
        recordings = recordings_of(lab.app)
        recordings.keeper.pause(True)
        recordings.keeper.start()
        browser = lab.browser(0)
        queue = take_control(browser)
        measured = live_path(lab, browser, pairs, drives)
        blocks = measured["blocks"]
        rows += ratio_rows("drive -> ack", [(state, drive) for state, drive, _ in blocks], args.quick)
        rows += ratio_rows("telemetry -> viewer", [(state, view) for state, _, view in blocks], args.quick)
        rows += cpu_rows(measured["cpu"])
        extra["cpu_s_per_s"] = measured["cpu"]
        extra["blocks"] = [{"state": state, "drive_p50_ms": percentile_ms(drive, 50), "drives": len(drive),
                            "viewer_p50_ms": percentile_ms(view, 50), "views": len(view)}
                           for state, drive, view in blocks]
        on_disk, own, seconds = bytes_window(lab, browser, window_s)
        rows.append(Measurement("recording size", "bytes per minute of session (disk)", on_disk, "B/min", "-", own,
                                None, f"floor: the messages' own bytes; a {seconds:.0f} s part, driving"))
        queue.send(json.dumps({"type": "leave"}))
        queue.close()
        long_id = synthetic_recording(lab, minutes * 60)
        short_id = synthetic_recording(lab, 10.0)
        times = replay_times(lab, long_id, short_id, 1 if args.quick else REPLAY_LOADS)
        label = f"replay page, {minutes:g} min"
        rows += [Measurement(label, "time to first frame", statistics.median(times["long"]["first_frame"]), "ms",
                             "-", statistics.median(times["short"]["first_frame"]), None,
                             "floor: the same page on a 10 s recording"),
                 Measurement(label, "whole recording loaded", statistics.median(times["long"]["ready"]), "ms", "-",
                             statistics.median(times["short"]["ready"]), None)]
        extra["replay_ms"] = times
        extra["load_average_at_end"] = os.getloadavg()
        recordings.stop()
    finally:
        lab.stop()
    print_table("Recording cost on the live path", rows)
    write_json(args.output / "recording_cost.json", rows, extra)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
