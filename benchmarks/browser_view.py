"""What the robot's-eye view drawn by the browser saves (issue 17). Server side, in one run: the CPU of one simulated
robot watched by one viewer, the skill server plus the web worker relaying its streams, with the browser-drawn view
(a telemetry viewer: the drawn view's only stream) and with the JPEG camera (a camera viewer, with the telemetry a
console takes anyway), the robot idle and driven; the floor is the same robot with nobody watching. Browser side: the
frame time of the robot's-eye view at 640x480 in headless Chromium (Debian's, `--disable-gpu`: WebGL in software),
the drawing alone and the console's whole frame (drawn-view.js: drawn, then taken as a bitmap). End to end: the
capture-to-glass delay of a pose update, from the skill server's capture time of a pose (Telemetry.capture_unix_s) to
the frame drawn from it on the console's canvas one animation frame later (the middleware, the WebSocket leg and the
drawing), beside the JPEG camera's capture-to-glass in the same console and run (the comparison); one machine, so
the skill server's and the browser's wall clocks are one clock.

    python -m benchmarks.browser_view [--quick] [--output DIR]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from benchmarks.report import Measurement, percentile_ms, print_table, write_json

TOKEN = "browser-view-bench"
VIEWERS = {"none": (), "drawn": ("telemetry",), "camera": ("camera", "telemetry")}
STATES = ("idle", "driven")
TARGET_RATIO = 1 / 8
VIEW_SIZE = (640, 480)
GLASS_SOURCES = (("video", "JPEG camera"), ("drawn", "drawn view"))
GLASS_GRACE_S = 10.0  # past the window, the wait for a source's first frame before the run fails


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def relay(address: str, streams: tuple[str, ...], ready, stop, received) -> None:
    """A web worker's share of one viewer: the robot's hubs for these streams, one subscriber each, read until stop."""
    from middleware.robots.link import RobotLink

    link = RobotLink("robot", address)
    viewers = [getattr(link, stream).subscribe() for stream in streams]
    count = 0
    ready.set()
    while not stop.is_set():
        for viewer in viewers:
            if viewer.next_message(0.05) is not None:
                count += 1
        if not viewers:
            time.sleep(0.05)
    received.value = count
    for viewer in viewers:
        viewer.close()
    link.close()


class Driver:
    """Drives the robot in a slow circle at 5 Hz, as a console holding a key sends commands, while `on` is set."""

    def __init__(self, address: str) -> None:
        from middleware.robots.link import RobotLink

        self._link = RobotLink("driver", address)
        self.on = threading.Event()
        self._stop = threading.Event()
        self._sequence = 0
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.2):
            if self.on.is_set():
                self._sequence += 1
                self._link.drive(TOKEN, self._sequence, 0.2, 0.4)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        self._link.close()


@contextmanager
def relaying(address: str, streams: tuple[str, ...]) -> Iterator[int | None]:
    """A web worker process relaying these streams to one viewer, while inside; its pid (None: no viewer, no worker)."""
    if not streams:
        yield None
        return
    # A new process, not a fork of this one (its threads and channels): a fork of a fork server that imported the
    # relay's code once, where a spawned one spent about 2 s of CPU importing the middleware.
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["middleware.robots.link"])
    stop, ready, received = context.Event(), context.Event(), context.Value("i", 0)
    process = context.Process(target=relay, args=(address, streams, ready, stop, received), daemon=True)
    process.start()
    try:
        if not ready.wait(60):
            raise RuntimeError("the relaying worker did not start")
        yield process.pid
    finally:
        stop.set()
        process.join(10)
    if received.value == 0:
        raise RuntimeError(f"the relaying worker received nothing of {streams}")


def measure(robot_pid: int, worker_pid: int | None, window_s: float) -> dict[str, float]:
    """CPU shares (of one core) of the robot and of its relaying worker over window_s."""
    def worker_cpu_s() -> float:
        return _cpu_s(worker_pid) if worker_pid is not None else 0.0

    robot_before, worker_before = _cpu_s(robot_pid), worker_cpu_s()
    started = time.perf_counter()
    time.sleep(window_s)
    elapsed = time.perf_counter() - started
    robot, worker = (_cpu_s(robot_pid) - robot_before) / elapsed, (worker_cpu_s() - worker_before) / elapsed
    return {"robot": robot, "worker": worker, "server": robot + worker}


def measure_servers(window_s: float, settle_s: float) -> tuple[dict[str, dict[str, dict[str, float]]], dict[str, Any]]:
    """({state: {viewer: figures}}, the scene as the browser receives it) for one robot on the lab scene, every figure
    from the same robot process."""
    from middleware.robots.link import RobotLink
    from middleware.robots.processes import SkillServerProcess
    from middleware.robots.scene import scene_dict

    robot = SkillServerProcess("browser-view", "lab", echo=False, controller_token=TOKEN)
    robot.serve()
    measured: dict[str, dict[str, dict[str, float]]] = {}
    try:
        assert robot.process is not None
        link = RobotLink("scene", robot.address)
        scene = scene_dict(link.scene(max_age_s=60.0))  # what GET /api/robots/<r>/scene serves
        link.close()
        driver = Driver(robot.address)
        try:
            for viewer, streams in VIEWERS.items():
                with relaying(robot.address, streams) as worker_pid:
                    for state in STATES:
                        if state == "driven":
                            driver.on.set()
                        else:
                            driver.on.clear()
                        # The streams flowing (the camera's renderer warm), and the robot at rest or in its circle.
                        time.sleep(settle_s)
                        measured.setdefault(state, {})[viewer] = measure(robot.process.pid, worker_pid, window_s)
            driver.on.clear()
        finally:
            driver.close()
    finally:
        robot.stop()
    return measured, scene


FRAME_TIMES = """async ([scene, size, frames, warmup]) => {
  const { RobotEyeRenderer } = await import('/lib/robot-eye.js');
  const { DrawnView } = await import('/panels/camera-panel/drawn-view.js');
  const canvas = document.createElement('canvas');
  document.body.append(canvas);
  const view = new RobotEyeRenderer(canvas, scene, { width_px: size[0], height_px: size[1] });
  const gl = canvas.getContext('webgl2') ?? canvas.getContext('webgl');
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const pixel = new Uint8Array(4);
  // A walk round the lab, turning as it goes: near walls, facing the crate, the pillar and the lanes.
  const poseAt = (i) => ({ x_m: 2.2 * Math.cos(i / 40), y_m: 1.6 * Math.sin(i / 40), theta_rad: (i / 40) + 1.9 });
  const draw = [];
  for (let i = 0; i < warmup + frames; i += 1) {
    const start = performance.now();
    view.render(poseAt(i));
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);  // waits until the frame is drawn
    if (i >= warmup) draw.push(performance.now() - start);
  }
  view.dispose();
  const scale = size[0] / scene.camera.width_px;
  const { view: drawn, problem } = await DrawnView.create(scene, scale);
  if (!drawn) throw new Error(problem);
  const whole = [];
  for (let i = 0; i < warmup + frames; i += 1) {
    const start = performance.now();
    const frame = await drawn.frameFrom({ odometry: { pose: poseAt(i) }, camera_pose: poseAt(i),
                                          capture_unix_s: Date.now() / 1000 });
    if (i >= warmup) whole.push(performance.now() - start);
    if (i === 0 && (frame.header.width_px !== size[0] || frame.header.height_px !== size[1])) {
      throw new Error(`drawn at ${frame.header.width_px}x${frame.header.height_px}`);
    }
    frame.bitmap.close();
  }
  drawn.dispose();
  return { draw, whole, renderer: info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER) };
}"""


@contextmanager
def chromium() -> Iterator[Any]:
    """Headless Chromium (Debian's, as the suite's), launched once for every page of the run."""
    from playwright.sync_api import sync_playwright

    from benchmarks.feedback import CHROMIUM_ARGS, CHROMIUM_PATH

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM_PATH, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


@contextmanager
def chromium_page(browser: Any) -> Iterator[tuple[Any, list[str]]]:
    """A tab at 1280x800 in a context of its own, and the JavaScript errors it raises."""
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    try:
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        yield page, errors
    finally:
        context.close()


def open_console(page: Any, base_url: str, username: str, password: str, robot: str = "lab-1") -> None:
    """Logs username in, as a person does, and opens the robot's console."""
    page.goto(f"{base_url}/login")
    page.fill("#username", username)
    page.fill("#password", password)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').first.wait_for(state="attached")
    page.goto(f"{base_url}/lab/{robot}")


def measure_browser(browser: Any, scene: dict[str, Any], frames: int, warmup: int) -> dict[str, Any]:
    """Frame times [ms] of the robot's-eye view at VIEW_SIZE in headless Chromium: {draw, whole, renderer}."""
    from benchmarks.feedback import static_server
    from middleware.browser_modules import import_map_text

    with static_server() as url, chromium_page(browser) as (page, errors):
        page.goto(f"{url}/lib/")
        page.evaluate("(text) => { const map = document.createElement('script'); map.type = 'importmap';"
                      " map.textContent = text; document.head.append(map); }", import_map_text("/"))
        answer: dict[str, Any] = page.evaluate(FRAME_TIMES, [scene, list(VIEW_SIZE), frames, warmup])
        if errors:
            raise RuntimeError(f"JavaScript errors while drawing: {errors}")
    return answer


# Each frame the console's camera panel puts on its canvas, stamped one animation frame later (when it is on the
# glass) with the capture time of what it shows: the pose's for a drawn frame, the camera's for a video frame.
GLASS_LISTENER = """() => {
  window.glassSamples = [];
  document.querySelector('camera-panel').addEventListener('camera-frame-shown', ({ detail }) => {
    requestAnimationFrame(() => window.glassSamples.push(
      { source: detail.source, capture_unix_s: detail.capture_unix_s, glass_unix_s: Date.now() / 1000 }));
  });
}"""


def measure_glass(browser: Any, window_s: float, warmup_s: float = 1.0) -> dict[str, list[float]]:
    """Capture-to-glass delays [ms] in a student's console in headless Chromium, the JPEG camera's for window_s, then
    the drawn view's for window_s, on one lab (skill server, middleware) started for it: {"video": [...], "drawn":
    [...]}."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeoutError

    from benchmarks.lab_under_test import PASSWORD, LabUnderTest

    lab = LabUnderTest(users=1)
    delays: dict[str, list[float]] = {}
    try:
        with chromium_page(browser) as (page, errors):
            open_console(page, lab.middleware.url, lab.usernames[0], PASSWORD)
            page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached", timeout=30_000)
            page.evaluate(GLASS_LISTENER)
            for source, _name in GLASS_SOURCES:
                if source == "drawn":
                    page.locator('[data-field="camera-source"]').select_option("drawn")
                    page.locator('camera-panel[data-frame-source="drawn"]').wait_for(state="attached")
                page.wait_for_timeout(warmup_s * 1000)  # the first frames of a source: its socket and renderer warming
                page.evaluate("() => { window.glassSamples = []; }")
                page.wait_for_timeout(window_s * 1000)
                try:  # a short (quick) window on a busy machine: the window lasts until the source's first frame
                    page.wait_for_function("(source) => window.glassSamples.some((s) => s.source === source)",
                                           arg=source, timeout=GLASS_GRACE_S * 1000)
                except PlaywrightTimeoutError:
                    waited_s = window_s + GLASS_GRACE_S
                    raise RuntimeError(f"no {source} frame reached the canvas in {waited_s} s") from None
                samples = page.evaluate("() => window.glassSamples")
                delays[source] = [1000 * (s["glass_unix_s"] - s["capture_unix_s"]) for s in samples
                                  if s["source"] == source]
            if errors:
                raise RuntimeError(f"JavaScript errors in the console: {errors}")
    finally:
        lab.stop()
    return delays


def glass_rows(delays: dict[str, list[float]]) -> list[Measurement]:
    """p50 and p99 of each source's capture-to-glass, the drawn view's beside the JPEG camera's as its floor."""
    scenario = "a pose to the glass, headless Chromium"
    rows = []
    for q in (50, 99):
        video = percentile_ms([ms / 1000 for ms in delays["video"]], q)
        for source, name in GLASS_SOURCES:
            rows.append(Measurement(
                scenario, f"capture to glass, {name}, p{q}", percentile_ms([ms / 1000 for ms in delays[source]], q),
                "ms", "-", floor=video if source == "drawn" else None,
                note=f"{len(delays[source])} frames" + (", the pose's capture time" if source == "drawn" else "")))
    return rows


def server_rows(measured: dict[str, dict[str, dict[str, float]]], quick: bool, load: float) -> list[Measurement]:
    """Per state: each viewer's server CPU beside the unwatched robot, the drawn view's share of the camera's, and what
    each view costs above the unwatched robot (its marginal cost) with the drawn view's share of the camera's."""
    rows = []
    for state in STATES:
        figures = measured[state]
        scenario = f"one robot, {state}, one viewer"
        headless = figures["none"]["server"]
        for viewer, name in (("drawn", "browser-drawn view (telemetry viewer)"),
                             ("camera", "JPEG camera (camera viewer)")):
            split = figures[viewer]
            rows.append(Measurement(scenario, f"server CPU, {name}", split["server"], "cores", "-", floor=headless,
                                    note=f"skill server {split['robot']:.3f} + worker {split['worker']:.3f}"))
        ratio = figures["drawn"]["server"] / figures["camera"]["server"]
        rows.append(Measurement(scenario, "server CPU, drawn view / JPEG camera", ratio, "ratio", "<= 1/8",
                                passed=None if quick else ratio <= TARGET_RATIO, note=f"load average {load:.1f}"))
        marginal = {viewer: figures[viewer]["server"] - headless for viewer in ("drawn", "camera")}
        for viewer, name in (("drawn", "drawn view"), ("camera", "JPEG camera")):
            rows.append(Measurement(scenario, f"marginal server CPU, {name} (minus unwatched)", marginal[viewer],
                                    "cores", "-", floor=headless))
        share = marginal["drawn"] / marginal["camera"] if marginal["camera"] > 0 else None
        rows.append(Measurement(scenario, "marginal server CPU, drawn view / JPEG camera", share, "ratio", "<= 1/8",
                                passed=None if quick or share is None else share <= TARGET_RATIO,
                                note="what the view itself costs the server"))
    return rows


def browser_rows(frames: dict[str, Any]) -> list[Measurement]:
    """p50 and p99 of the drawing alone and of the console's whole drawn frame."""
    scenario = f"robot's-eye view {VIEW_SIZE[0]}x{VIEW_SIZE[1]}, headless Chromium"
    note = f"WebGL: {frames['renderer']}"
    rows = []
    for key, name in (("draw", "frame time, drawing"), ("whole", "frame time, drawn + taken as bitmap")):
        samples_s = [ms / 1000 for ms in frames[key]]
        rows += [Measurement(scenario, f"{name}, p50", percentile_ms(samples_s, 50), "ms", "-", note=note),
                 Measurement(scenario, f"{name}, p99", percentile_ms(samples_s, 99), "ms", "-")]
    return rows


def run(quick: bool, output: Path) -> list[Measurement]:
    window_s, settle_s = (0.5, 0.3) if quick else (10.0, 2.0)
    frames, warmup = (10, 3) if quick else (300, 30)
    glass_window_s, glass_warmup_s = (1.0, 0.5) if quick else (30.0, 1.0)
    measured, scene = measure_servers(window_s, settle_s)
    load = os.getloadavg()[0]
    with chromium() as chromium_browser:
        browser = measure_browser(chromium_browser, scene, frames, warmup)
        glass = measure_glass(chromium_browser, glass_window_s, glass_warmup_s)
    rows = server_rows(measured, quick, load) + browser_rows(browser) + glass_rows(glass)
    print_table("The robot's-eye view drawn by the browser: server CPU per watched robot, browser frame time, and a "
                "pose's capture to glass", rows)
    output.mkdir(parents=True, exist_ok=True)
    write_json(output / "browser_view.json", rows, {
        "quick": quick, "window_s": window_s, "frames": frames, "warmup_frames": warmup, "load_average": load,
        "webgl_renderer": browser["renderer"], "measured": measured,
        "frame_times_ms": {key: [round(ms, 3) for ms in browser[key]] for key in ("draw", "whole")},
        "glass_window_s": glass_window_s,
        "capture_to_glass_ms": {source: [round(ms, 3) for ms in delays] for source, delays in glass.items()},
        "cpu_count": os.cpu_count()})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
