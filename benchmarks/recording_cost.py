"""What recording every session costs (issue 30), each figure beside a floor measured in the same run:

- the live path: drive -> ack and telemetry -> viewer latency with the recorder off and on, in blocks that
  alternate off/on, on/off, ... (so both see the machine in the same state; the machine is shared), each pair
  giving a ratio of the on p50 to the off p50 (and of the p99s). The figure is the median of the pairs' p50 ratios
  with a distribution-free 95 % interval for it (order statistics, the sign test's binomial: no assumption about
  the host's noise), graded by the interval: within 1.05 when all of it is, a miss when all of it is over, and
  undecided when it straddles 1.05 (more pairs narrow it: `--pairs`). The floor of each latency is the off blocks'
  own. During every block a console watches the robot's telemetry (its socket is the telemetry -> viewer sample)
  while the drive pad sends, as in a session. "Off" is the keeper paused (no tap, no command notes; its tick goes
  on), "on" the keeper recording lab-1's turn. The client's sockets are read by threads of this process, which also
  serves the middleware: what the recorder costs the interpreter, the client pays too (a browser would not), so the
  ratios are an upper bound. Each block's load average is kept in the JSON: the machine is shared.
- CPU time, which a loaded machine slows but does not add to: the recorder's threads in the worker (the keeper's
  tick; the interpreter the live path shares) beside the 0 floor, each thread by its own CPU clock; the channel
  loop's thread (the tap's, and every console socket's), on minus off in each pair; the worker's whole CPU, on over
  off; the writer child's (middleware/recordings/writer.py), each with its 95 % interval.
- bytes per minute of session: one part recorded while driving with the console open, against the floor of its
  messages' own bytes (serialized, before MCAP's framing and zstd).
- the replay page's time to first frame for a 30-minute recording (10 Hz odometry, truth, sonar and laser with
  lab-1's sensor counts, a command a second; written synthetically through the recorder's own `files.PartWriter`,
  a chunk a second as the recorder closes them), in headless Chromium: from the navigation's start to the browser
  frame after the page marks its first frame, against the floor of the same page on a 10-second recording; and
  the time until the whole recording is loaded behind it.

Run `python -m benchmarks.recording_cost [--quick] [--pairs N] [--live-only] [--output DIR]`: prints a table, writes
DIR/recording_cost.json.
"""

from __future__ import annotations

import argparse
import io
import json
import math
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
PAIRS, DRIVES = 40, 150  # 40 pairs: the median's 95 % interval spans the 14th to 27th of the sorted pair ratios
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
    from middleware.recordings.parts import recordings_of

    recordings = recordings_of(lab.app)
    recordings._active = on  # noqa: SLF001 - the command path's observer notes commands only while on
    recordings.keeper.pause(not on)  # the keeper's thread (a pass every CHECK_S) applies it
    deadline = time.monotonic() + 15
    while bool(recordings.keeper.recording_now()) != on:
        if time.monotonic() > deadline:
            raise RuntimeError(f"the recorder did not turn {'on' if on else 'off'}")
        time.sleep(0.05)
    time.sleep(SETTLE_ON_S if on else SETTLE_OFF_S)


# The recorder's own threads in the worker: the keeper's (now its only one); the command log's thread and the
# recorder pool's before (counted when they exist, so the same harness measures the code before and after).
RECORDER_THREADS = ("recordings", "command-log", "recorder-io")
LOOP_THREAD = "channel-loop"  # the tap's thread (every console's sockets and hubs run on it too)
CONFIDENCE = 0.95


def _stat_cpu_s(path: Path) -> float:
    """utime + stime of a /proc stat file, in seconds (0 when it is gone)."""
    try:
        fields = path.read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0  # it just ended: the next block counts its successor


def _thread_cpu_s() -> dict[int, tuple[str, float]]:
    """Each live thread of this process: its name and CPU seconds so far (its own CPU clock: nanoseconds, not ticks)."""
    found = {}
    for thread in threading.enumerate():
        if thread.ident is None:
            continue
        try:
            found[thread.ident] = (thread.name, time.clock_gettime(time.pthread_getcpuclockid(thread.ident)))
        except (OSError, ProcessLookupError):
            continue  # it just ended
    return found


def cpu_seconds(lab: LabUnderTest) -> dict[str, Any]:
    """CPU seconds so far: this process ("worker": the middleware, its recorder and the benchmark's client), its
    recording writer child, and each thread of this process."""
    from middleware.recordings.parts import recordings_of

    pid = recordings_of(lab.app).keeper.writer.pid
    child = _stat_cpu_s(Path(f"/proc/{pid}/stat")) if pid is not None else 0.0
    return {"worker": time.process_time(), "writer_child": child, "threads": _thread_cpu_s()}


def cpu_shares(started: dict[str, Any], ended: dict[str, Any], wall_s: float) -> dict[str, float]:
    """CPU seconds a second over a block: the worker, the writer child, the recorder's threads, the channel loop."""
    def threads(prefixes: tuple[str, ...]) -> float:
        return sum(cpu - started["threads"].get(ident, (name, 0.0))[1]
                   for ident, (name, cpu) in ended["threads"].items() if name.startswith(prefixes))

    return {"worker": (ended["worker"] - started["worker"]) / wall_s,
            "writer_child": max(0.0, ended["writer_child"] - started["writer_child"]) / wall_s,
            "recorder_threads": threads(RECORDER_THREADS) / wall_s, "loop_thread": threads((LOOP_THREAD,)) / wall_s}


def live_path(lab: LabUnderTest, browser: Browser, pairs: int, drives: int) -> dict[str, Any]:
    """Alternating off/on blocks; every block's drive and viewer samples, its CPU a second (the worker, its writer
    child, the recorder's threads, the channel loop) and the load average at its end."""
    blocks: list[tuple[str, list[float], list[float]]] = []
    parts: list[tuple[str, dict[str, float]]] = []
    loads: list[float] = []
    viewer = TelemetryViewer(browser)
    try:
        for pair in range(pairs):
            for state in (("off", "on") if pair % 2 == 0 else ("on", "off")):
                switch(lab, state == "on")
                viewer.take()
                cpu_started, started = cpu_seconds(lab), time.monotonic()
                drive = measure_drive(browser, drives)
                parts.append((state, cpu_shares(cpu_started, cpu_seconds(lab), time.monotonic() - started)))
                blocks.append((state, drive, viewer.take()))
                loads.append(os.getloadavg()[0])
    finally:
        viewer.close()
    return {"blocks": blocks, "cpu_parts": parts, "loads": loads}


def median_interval(values: list[float], confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """(low, median, high): the median of values and a distribution-free interval for the median of what they were
    drawn from, at confidence or more (order statistics: x(k) and x(n+1-k), k from the sign test's binomial); low and
    high are nan when there are too few values for that confidence (fewer than 6 at 95 %)."""
    ordered = sorted(values)
    n = len(ordered)
    if not n:
        return math.nan, math.nan, math.nan
    tail, below, k = (1 - confidence) / 2, 0.0, 0
    while k < n and below + math.comb(n, k) / 2 ** n <= tail:
        below += math.comb(n, k) / 2 ** n
        k += 1
    median = statistics.median(ordered)
    return (ordered[k - 1], median, ordered[n - k]) if k >= 1 else (math.nan, median, math.nan)


def within(interval: tuple[float, float, float], target: float) -> bool | None:
    """True when the whole interval is at or under target, False when it is all over it, None when it straddles it
    (the run cannot tell at its confidence)."""
    low, _, high = interval
    if math.isnan(low):
        return None
    return True if high <= target else False if low > target else None


def _said(interval: tuple[float, float, float], count: int, what: str = "pairs") -> str:
    low, _, high = interval
    if math.isnan(low):
        return f"{count} {what}: too few for a {CONFIDENCE:.0%} interval"
    return f"{CONFIDENCE:.0%} interval {low:.3f}-{high:.3f} ({count} {what})"


def pair_values(parts: list[tuple[str, Any]]) -> list[tuple[Any, Any]]:
    """(on, off) of each pair of consecutive blocks."""
    found = []
    for index in range(0, len(parts) - 1, 2):
        pair = dict(parts[index:index + 2])
        if "on" in pair and "off" in pair:
            found.append((pair["on"], pair["off"]))
    return found


def cpu_rows(parts: list[tuple[str, dict[str, float]]]) -> list[Measurement]:
    """CPU time, which a loaded machine slows but does not add to (steadier than latencies on a shared machine): the
    recorder's threads in the worker beside the 0 floor; the channel loop's thread (where the tap runs) and the
    worker's whole CPU, on against off in each pair; the writer child's."""
    pairs = pair_values(parts)
    if not pairs:
        return []
    recorder = median_interval([on["recorder_threads"] * 1000 for on, _ in pairs])
    loop = median_interval([(on["loop_thread"] - off["loop_thread"]) * 1000 for on, off in pairs])
    worker = median_interval([on["worker"] / off["worker"] for on, off in pairs if off["worker"] > 0])
    added = median_interval([(on["worker"] - off["worker"]) * 1000 for on, off in pairs])
    child = median_interval([on["writer_child"] * 1000 for on, _ in pairs])
    n = len(pairs)
    return [
        Measurement("recorder's threads in the worker", "CPU a second, recording on (median of blocks)", recorder[1],
                    "ms/s", "-", 0.0, None, f"{', '.join(RECORDER_THREADS)}; {_said(recorder, n, 'blocks')}"),
        Measurement("channel loop (the tap's thread)", "CPU a second, on - off (median of pairs)", loop[1], "ms/s",
                    "-", 0.0, None, f"{_said(loop, n)}; the consoles' sockets run on it too"),
        Measurement("worker process CPU", "on / off (median of pairs)", worker[1], "x", "-", 1.0, None,
                    f"{_said(worker, n)}; adds {added[1]:.1f} ms/s ({added[0]:.1f}-{added[2]:.1f}); the benchmark's "
                    "client is in the process too"),
        Measurement("recording writer child", "CPU a second, recording on (median of blocks)", child[1], "ms/s", "-",
                    0.0, None, f"a process of its own: not the worker's interpreter; {_said(child, n, 'blocks')}"),
    ]


def ratio_rows(name: str, blocks: list[tuple[str, list[float]]], quick: bool) -> list[Measurement]:
    """The pooled p50/p99 on beside off; the median of the pairs' p50 ratios with its interval, graded by it (within
    1.05 only when the whole interval is), and the same for the p99 ratios (reported)."""
    on = [s for state, samples in blocks if state == "on" for s in samples]
    off = [s for state, samples in blocks if state == "off" for s in samples]
    pairs = [(a, b) for a, b in pair_values(blocks) if a and b]
    ratios = {q: [percentile_ms(a, q) / percentile_ms(b, q) for a, b in pairs] for q in (50, 99)}
    p50, p99 = median_interval(ratios[50]), median_interval(ratios[99])
    verdict = None if quick else within(p50, RATIO_TARGET)
    undecided = "" if quick or verdict is not None else f"; undecided: the interval straddles {RATIO_TARGET}"
    return [
        Measurement(f"{name}, recording on", "p50", percentile_ms(on, 50), "ms", "-", percentile_ms(off, 50)),
        Measurement(f"{name}, recording on", "p99", percentile_ms(on, 99), "ms", "-", percentile_ms(off, 99)),
        Measurement(name, "p50 on / p50 off, median of pairs", p50[1], "x", f"<= {RATIO_TARGET} at {CONFIDENCE:.0%}",
                    1.0, verdict, _said(p50, len(pairs)) + undecided),
        Measurement(name, "p99 on / p99 off, median of pairs", p99[1], "x", "-", 1.0, None, _said(p99, len(pairs))),
    ]


def bytes_window(lab: LabUnderTest, browser: Browser, window_s: float) -> tuple[float, float, float]:
    """One part recorded over window_s of driving with the console open, completed: (bytes a minute on disk,
    the messages' own bytes a minute, the part's seconds)."""
    from middleware.recordings import files
    from middleware.recordings.parts import recordings_of

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
    from middleware.recordings import channels, files
    from middleware.recordings.parts import recordings_of
    from middleware.robots.registry import robot_registry
    from protos.telelab.v1 import robot_pb2

    link = robot_registry(lab.app).get("lab-1")
    assert link is not None, "the lab under test has lab-1"
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
    parser.add_argument("--pairs", type=int, help=f"on/off pairs (default {PAIRS}; 2 with --quick)")
    parser.add_argument("--live-only", action="store_true", help="the live path's figures only (no size, no replay)")
    args = parser.parse_args(argv)
    from middleware.recordings.parts import recordings_of

    # Quick: 3 s of driving, a part of about 6 s with the recorder's settling (683 kB a minute, against 687 with 15 s
    # of driving, one run each): the smoke run sizes a part and grades nothing.
    pairs, drives, window_s, minutes = (2, 40, 3.0, 3.0) if args.quick else (PAIRS, DRIVES, 60.0, 30.0)
    pairs = args.pairs or pairs
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
        rows += cpu_rows(measured["cpu_parts"])
        extra["cpu_parts_s_per_s"] = measured["cpu_parts"]
        extra["load_average_per_block"] = measured["loads"]
        extra["blocks"] = [{"state": state, "drive_p50_ms": percentile_ms(drive, 50),
                            "drive_p99_ms": percentile_ms(drive, 99), "drives": len(drive),
                            "viewer_p50_ms": percentile_ms(view, 50), "viewer_p99_ms": percentile_ms(view, 99),
                            "views": len(view)} for state, drive, view in blocks]
        extra["load_average_at_live_end"] = os.getloadavg()
        if args.live_only:
            recordings.stop()
            return 0
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
