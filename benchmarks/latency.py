"""Response time, streaming and capacity of the lab on loopback, each beside a floor measured in the same run.

Run `python -m benchmarks.latency [--quick] [--output DIR]`: prints a table, writes DIR/latency.json and a
PNG histogram per latency scenario. Anchors: the 2003 paper's table 1 (138 ms total on a LAN; 10.89 ms
middleware to skill server) and web_video_server, which encodes once per viewer.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import statistics
import threading
import time
from pathlib import Path

import grpc
import simple_websocket

from benchmarks.lab_under_test import Browser, LabUnderTest, WebSocketClient
from benchmarks.report import Measurement, percentile_ms, print_table, write_histogram_png, write_json
from middleware.robots.messages import unpack_camera_frame
from middleware.robots.registry import robot_registry
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

FIRST_FRAME_GRACE_S = 10.0


def take_control(browser: Browser) -> simple_websocket.Client:
    """Joins the queue and waits for control; the socket keeps the seat."""
    queue = browser.websocket("/ws/robots/lab-1/queue")
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        message = json.loads(queue.receive(timeout=10))
        if message.get("type") == "queue" and message["is_controller"]:
            return queue
    raise RuntimeError("the benchmark user never got control")


def latency_rows(scenario: str, samples_s: list[float], floor_s: list[float] | None, p50_target_ms: float,
                 p99_target_ms: float, quick: bool, ratio_target: float | None = None) -> list[Measurement]:
    """p50 and p99 rows (and the ratio to the floor) for one scenario."""
    def verdict(ok: bool) -> bool | None:
        return None if quick else ok

    p50, p99 = percentile_ms(samples_s, 50), percentile_ms(samples_s, 99)
    floor50 = percentile_ms(floor_s, 50) if floor_s else None
    floor99 = percentile_ms(floor_s, 99) if floor_s else None
    rows = [
        Measurement(scenario, "p50", p50, "ms", f"<= {p50_target_ms:g}", floor50, verdict(p50 <= p50_target_ms)),
        Measurement(scenario, "p99", p99, "ms", f"<= {p99_target_ms:g}", floor99, verdict(p99 <= p99_target_ms)),
    ]
    if ratio_target is not None and floor50:
        ratio = p50 / floor50
        rows.append(Measurement(scenario, "p50 / floor p50", ratio, "x", f"<= {ratio_target:g}", None,
                                verdict(ratio <= ratio_target)))
    return rows


def measure_floors(lab: LabUnderTest, count: int) -> dict[str, list[float]]:
    """A bare Flask route, a bare gRPC unary call, and a bare WebSocket echo, on this machine now (the floor of
    the activation path is measured with it, interleaved)."""
    http = [lab.floor_request() for _ in range(count)]
    with grpc.insecure_channel(lab.robot.address) as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=5)
        unary = []
        for _ in range(count):
            started = time.perf_counter()
            stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=5)
            unary.append(time.perf_counter() - started)
    echo_socket = WebSocketClient.connect(lab.floor.url.replace("http", "ws", 1) + "/echo")
    echo = []
    for n in range(count):
        started = time.perf_counter()
        echo_socket.send(str(n))
        echo_socket.receive(timeout=5)
        echo.append(time.perf_counter() - started)
    echo_socket.close()
    return {"http": http, "grpc": unary, "websocket": echo}


def measure_activation(lab: LabUnderTest, browser: Browser,
                       count: int) -> tuple[list[float], list[float], list[float]]:
    """HTTP client -> middleware -> gRPC -> skill accepted; the gRPC leg alone with the same request; and, one
    request before each activation, the floor of that path (a bare route making one bare gRPC call, same
    client), so that both see the machine in the same state."""
    from middleware.access.coordinator import access_coordinator

    total, relay = [], []
    for n in range(count):
        heading = 0.2 if n % 2 else -0.2
        body = {"parameters": {"heading_rad": heading}, "preempt": True}
        relay.append(lab.floor_request("/relay", json.dumps(body).encode()))
        started = time.perf_counter()
        status, answer = browser.post_json("/api/robots/lab-1/skills/orientation_control/goals", body)
        total.append(time.perf_counter() - started)
        if status != 202:
            raise RuntimeError(f"activation refused: {status} {answer}")
    token = access_coordinator(lab.app).snapshot("lab-1").token
    leg = []
    with grpc.insecure_channel(lab.robot.address) as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        for n in range(count):
            request = robot_pb2.ActivateSkillRequest(
                token=token or "", skill="orientation_control", preempt=True,
                parameters={"heading_rad": robot_pb2.ParameterValue(double_value=0.2 if n % 2 else -0.2)})
            started = time.perf_counter()
            stub.ActivateSkill(request, timeout=5)
            leg.append(time.perf_counter() - started)
    return total, leg, relay


def measure_drive(browser: Browser, count: int) -> list[float]:
    """WebSocket drive command -> acknowledged by the skill server (applied at its next control tick)."""
    drive = browser.websocket("/ws/robots/lab-1/drive")
    json.loads(drive.receive(timeout=10))
    samples = []
    for sequence in range(1, count + 1):
        started = time.perf_counter()
        drive.send(json.dumps({"type": "drive", "sequence": sequence, "linear_mps": 0.0, "angular_radps": 0.0}))
        answer = json.loads(drive.receive(timeout=5))
        samples.append(time.perf_counter() - started)
        if answer["type"] != "ack":
            raise RuntimeError(f"drive refused: {answer}")
        time.sleep(0.02)
    drive.close()
    return samples


def measure_camera(browser: Browser, duration_s: float) -> list[tuple[float, float]]:
    """(arrival time, capture -> delivered latency) of every frame a viewer socket receives."""
    camera = browser.websocket("/ws/robots/lab-1/camera")
    samples = []
    end = time.monotonic() + duration_s
    # A short (quick) window on a busy machine lasts until the first frame, as long as FIRST_FRAME_GRACE_S more.
    while time.monotonic() < end or (not samples and time.monotonic() < end + FIRST_FRAME_GRACE_S):
        message = camera.receive(timeout=2)
        if isinstance(message, bytes):
            header, _ = unpack_camera_frame(message)
            samples.append((time.monotonic(), time.time() - float(header["capture_unix_s"])))
    camera.close()
    return samples


def measure_fanout(lab: LabUnderTest, browsers: list[Browser], viewers: int, duration_s: float,
                   settle_s: float = 1.0) -> tuple[float, float]:
    """(frames per second at one measured viewer, middleware packs per frame) with `viewers` others watching."""
    hub = robot_registry(lab.app).get("lab-1").camera
    sockets = [browsers[i % len(browsers)].websocket("/ws/robots/lab-1/camera") for i in range(viewers)]
    stop = threading.Event()

    def drain() -> None:
        while not stop.is_set():
            for sock in sockets:
                while sock.receive(timeout=0) is not None:
                    pass
            time.sleep(0.01)

    drainer = threading.Thread(target=drain, daemon=True)
    drainer.start()
    measured = browsers[0].websocket("/ws/robots/lab-1/camera")
    time.sleep(settle_s)
    while measured.receive(timeout=0) is not None:
        pass  # frames queued while the viewers settled are not part of the measurement
    packed_before = hub.messages_packed
    first = last = None
    frames = 0
    end = time.monotonic() + duration_s
    while time.monotonic() < end:
        message = measured.receive(timeout=2)
        if isinstance(message, bytes):
            sequence = int(unpack_camera_frame(message)[0]["frame_sequence"])
            first = sequence if first is None else first
            last = sequence
            frames += 1
    packed = hub.messages_packed - packed_before
    stop.set()
    drainer.join(2)
    for sock in [measured, *sockets]:
        sock.close()
    produced = (last - first + 1) if first is not None and last is not None else 0
    return frames / duration_s, packed / max(produced, 1)


def _capacity_load(base_url: str, usernames: list[str], watch: bool, duration_s: float, results,
                   go) -> None:
    """One load-generator process: its users log in, then watch telemetry or poll the robot's state."""
    browsers = [Browser(base_url, name) for name in usernames]
    latencies: list[float] = []
    errors = 0
    stop = threading.Event()
    lock = threading.Lock()

    def poll(browser: Browser, phase_s: float) -> None:
        # Independent people: each polls once a second from a phase of their own (all in step would be a
        # burst of every user's request at once, each second, which no class produces).
        nonlocal errors
        due = time.monotonic() + phase_s
        while not stop.wait(max(0.0, due - time.monotonic())):
            due += 1.0
            started = time.perf_counter()
            try:
                status, _ = browser.get("/api/robots/lab-1")
            except Exception:  # noqa: BLE001 - counted as an error
                status = 0
            with lock:
                latencies.append(time.perf_counter() - started)
                errors += status != 200

    def drain(sockets: list[simple_websocket.Client]) -> None:
        while not stop.is_set():
            for sock in sockets:
                while sock.receive(timeout=0) is not None:
                    pass
            time.sleep(0.02)

    if watch:
        sockets = [b.websocket("/ws/robots/lab-1/telemetry") for b in browsers]
        threads = [threading.Thread(target=drain, args=(sockets,), daemon=True)]
    else:
        sockets = []
        phases = random.Random(len(usernames)).sample(range(1000), len(browsers))
        threads = [threading.Thread(target=poll, args=(b, phase / 1000), daemon=True)
                   for b, phase in zip(browsers, phases, strict=True)]
    results.put(("ready", 0))
    go.wait(600)  # every user of both processes has logged in: logins hash passwords and would skew the load
    for thread in threads:
        thread.start()
    time.sleep(duration_s)
    stop.set()
    for thread in threads:
        thread.join(5)
    for sock in sockets:
        sock.close()
    results.put(("done", (latencies, errors)))


def measure_capacity(lab: LabUnderTest, usernames: list[str], duration_s: float) -> tuple[list[float], int, float]:
    """Half the users watch telemetry at 10 Hz, the others poll the robot's state each second.

    The load runs in two processes of its own, so the generator's threads do not share the middleware's
    interpreter (and GIL) and inflate what is measured.
    """
    import multiprocessing

    # New processes, not forks of this one (its threads and sockets): forks of a fork server that imported this module
    # once. Spawned, each load process spent about 2 s of CPU importing the middleware before its users logged in.
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["benchmarks.latency"])
    results = context.Queue()
    go = context.Event()
    half = len(usernames) // 2
    workers = [
        context.Process(target=_capacity_load, args=(lab.middleware.url, usernames[:half], True, duration_s, results,
                                                     go)),
        context.Process(target=_capacity_load, args=(lab.middleware.url, usernames[half:], False, duration_s,
                                                     results, go)),
    ]
    for worker in workers:
        worker.start()
    outcomes = [results.get(timeout=600) for _ in workers]
    cpu_before, wall_before = cpu_seconds(os.getpid()), time.monotonic()
    go.set()
    outcomes += [results.get(timeout=600) for _ in workers]
    middleware_cpu_share = (cpu_seconds(os.getpid()) - cpu_before) / (time.monotonic() - wall_before) * 100
    for worker in workers:
        worker.join(30)
    latencies: list[float] = []
    errors = 0
    for kind, payload in outcomes:
        if kind == "done":
            latencies += payload[0]
            errors += payload[1]
    return latencies, errors, middleware_cpu_share


BENCH_LESSON_CUES = """WEBVTT

00:00:00.000 --> 00:00:05.000
{"drive": {"linear_mps": 0.05, "angular_radps": 0.0}}

00:00:05.000 --> 00:00:10.000
{"stop": true}
"""


def create_bench_lesson(lab: LabUnderTest) -> int:
    """A lesson with a drive cue, saved through the same checks the lesson editor uses."""
    from middleware.db import session_factory
    from middleware.teaching.lessons import check_lesson, save_lesson
    from middleware.teaching.targets import reference_skills

    videos = Path(lab.app.instance_path) / "lessons"
    videos.mkdir(parents=True, exist_ok=True)
    (videos / "bench.webm").write_bytes(b"")
    with lab.app.app_context():
        draft = check_lesson({"title": "Benchmark lesson", "video_name": "bench.webm", "cues": BENCH_LESSON_CUES},
                             reference_skills(), ["bench.webm"])
        with session_factory(lab.app)() as session:
            lesson = save_lesson(session, draft, None)
            session.commit()
            return lesson.id


def measure_lesson(lab: LabUnderTest, browser: Browser, count: int) -> tuple[list[float], list[float]]:
    """Cue entered -> the robot acknowledged its command, and pause -> the robot acknowledged the stop.

    Measured from the request the lesson page sends on the TextTrack event to the skill server's
    answer; the browser's own event detection is measured by the lesson end-to-end test.
    """
    lesson_id = create_bench_lesson(lab)
    cue, pause = [], []
    for _ in range(count):
        started = time.perf_counter()
        status, body = browser.post_json(f"/api/lessons/{lesson_id}/cues/1/run", {"target": "lab-1", "hold_s": 2})
        cue.append(time.perf_counter() - started)
        if status != 202:
            raise RuntimeError(f"cue refused: {status} {body}")
        started = time.perf_counter()
        status, body = browser.post_json("/api/lessons/stop", {"target": "lab-1"})
        pause.append(time.perf_counter() - started)
        if status != 200:
            raise RuntimeError(f"stop refused: {status} {body}")
    return cue, pause


def headless_speed(sim_s: float) -> float:
    """How many times faster than real time the lab world runs headless (physics and sensors)."""
    from skill_server.sim.world import World

    world = World("lab", seed=0, realtime=False, deadman_timeout_s=1000.0)
    started = time.perf_counter()
    world.step_for(sim_s)
    speed = sim_s / (time.perf_counter() - started)
    world.stop()
    return speed


def cpu_seconds(pid: int) -> float:
    """User plus system CPU time of a process so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def camera_cpu_share(lab: LabUnderTest, browser: Browser, duration_s: float, settle_s: float = 1.0) -> float:
    """Percent of one core the real-time skill server uses while one viewer watches at 15 fps."""
    pid = lab.robot.process.pid
    viewer = browser.websocket("/ws/robots/lab-1/camera")
    time.sleep(settle_s)
    cpu_before, wall_before = cpu_seconds(pid), time.monotonic()
    while time.monotonic() < wall_before + duration_s:
        viewer.receive(timeout=1)
    share = (cpu_seconds(pid) - cpu_before) / (time.monotonic() - wall_before) * 100
    viewer.close()
    return share


def run(quick: bool, output: Path) -> list[Measurement]:
    """Every scenario; quick mode makes each short and grades nothing."""
    users = 10 if quick else 200
    settle_s = 0.5 if quick else 1.0  # viewers' streams flowing before a window
    count = 30 if quick else 300
    lab = LabUnderTest(users)
    rows: list[Measurement] = []
    histograms: dict[str, list[float]] = {}
    try:
        floors = measure_floors(lab, count)
        controller = lab.browser(0)
        queue = take_control(controller)

        total, leg, relay = measure_activation(lab, controller, count)
        # Its floor is the least an HTTP -> gRPC path costs: a bare route making one bare unary call.
        rows += latency_rows("skill activation (total)", total, relay, 5, 20, quick, ratio_target=1.5)
        rows.append(Measurement("skill activation (total)", "p50 / bare route p50",
                                percentile_ms(total, 50) / percentile_ms(floors["http"], 50), "x", "reported",
                                percentile_ms(floors["http"], 50), None, "floor: a route that does nothing"))
        rows += latency_rows("skill activation (gRPC leg)", leg, floors["grpc"], 5, 20, quick)
        rows.append(Measurement("skill activation (HTTP leg)", "p50 total - p50 gRPC leg",
                                percentile_ms(total, 50) - percentile_ms(leg, 50), "ms", "reported",
                                percentile_ms(floors["http"], 50)))
        histograms["skill_activation"] = total

        cue, pause = measure_lesson(lab, controller, count // 3)
        rows += latency_rows("lesson cue -> robot acknowledged", cue, floors["http"], 30, 80, quick)
        rows += latency_rows("pause -> robot stop acknowledged", pause, floors["http"], 50, 50, quick)[1:]
        histograms["lesson_cue"], histograms["pause_stop"] = cue, pause

        drive = measure_drive(controller, count)
        rows += latency_rows("direct command (WS -> ack)", drive, floors["websocket"], 10, 30, quick)
        histograms["direct_command"] = drive

        camera = measure_camera(controller, 1.0 if quick else 60.0)
        camera_latency = [latency for _, latency in camera]
        rows += latency_rows("camera capture -> viewer", camera_latency, None, 60, 150, quick)
        third = max(len(camera_latency) // 3, 1)
        growth = percentile_ms(camera_latency[-third:], 50) - percentile_ms(camera_latency[:third], 50)
        rows.append(Measurement("camera capture -> viewer", "p50 growth, last third - first", growth, "ms",
                                "<= 10 (no growth)", None, None if quick else growth <= 10))
        histograms["camera"] = camera_latency

        # Each logs in (a password hash on the server); the viewers' sockets are spread over them.
        viewer_browsers = [lab.browser(i) for i in range(1, 4 if quick else min(users, 10))]
        for viewers in ((1, 10) if quick else (1, 10, 50, 100)):
            fps, packs = measure_fanout(lab, viewer_browsers, viewers, 1.0 if quick else 10.0, settle_s)
            rows.append(Measurement(f"fan-out, {viewers} viewers", "frames per second at a viewer", fps, "fps",
                                    ">= 14 at 50 viewers", None, None if quick or viewers != 50 else fps >= 14))
            rows.append(Measurement(f"fan-out, {viewers} viewers", "middleware packs per frame", packs, "count",
                                    "= 1", None, None if quick else math.isclose(packs, 1.0, abs_tol=0.05),
                                    "the skill server JPEG-encodes each frame once"))

        latencies, errors, cpu_share = measure_capacity(lab, lab.usernames, 1.5 if quick else 30.0)
        rows += latency_rows(f"capacity, {users} users", latencies, floors["http"], 100, 100, quick)[1:]
        rows.append(Measurement(f"capacity, {users} users", "errors", float(errors), "count", "= 0", None,
                                None if quick else errors == 0))
        rows.append(Measurement(f"capacity, {users} users", "middleware process CPU", cpu_share, "% of a core",
                                "reported", None, None, "the skill server and the load run in other processes"))
        histograms["capacity_api"] = latencies
        queue.close()

        speed = headless_speed(1.5 if quick else 20.0)
        rows.append(Measurement("world, headless physics + sensors", "speed", speed, "x real time", ">= 20", None,
                                None if quick else speed >= 20))
        share = camera_cpu_share(lab, controller, 1.0 if quick else 10.0, settle_s)
        rows.append(Measurement("world, real time + camera 15 fps", "CPU of one core", share, "%", "<= 60", None,
                                None if quick else share <= 60))
    finally:
        lab.stop()
    for name, samples in histograms.items():
        write_histogram_png(output / f"latency-{name}.png", [s * 1000 for s in samples])
    write_json(output / "latency.json", rows, {"quick": quick, "users": users, "samples_per_scenario": count,
                                               "cpu_count": os.cpu_count(),
                                               "camera_latency_mean_ms": statistics.fmean(camera_latency) * 1000
                                               if camera_latency else None})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.latency", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    args = parser.parse_args(argv)
    rows = run(args.quick, args.output)
    print_table("Response time, streaming and capacity (loopback)", rows)
    print(f"\nJSON and histograms in {args.output}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
