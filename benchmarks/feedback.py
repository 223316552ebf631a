"""The camera feedback layer: how well its warp predicts the delayed video, and what it costs per frame.

Run `python -m benchmarks.feedback [--quick] [--output DIR]`: prints a table, writes DIR/feedback.json.

Prediction quality. A scripted drive per motion type (the console's default speed, 50 %: 0.25 m/s, 0.75 rad/s)
runs in the simulator in fast mode with seeded noise; commands go at 20 Hz as the console sends them (one
stop on release). At several moments the frame captured `delay` seconds ago (the stale frame, which shows
the commands up to its last_applied_sequence) is warped by the product's own code in headless Chromium: the
camera panel's FeedbackLayer is fed the commands sent since the drive began, the frame's header and the laser
scan taken with it, its transform (feedback-math.js) is drawn by the panel's drawWarped (edges continued, the
console's default), and the pixels are read back. The warped and the unwarped stale frame are compared with
the frame the simulator renders at the present moment: mean absolute error over every pixel and RGB channel
(0-255), graded warped < stale. Info rows: the same with the black fill (the thesis's, the console's other
choice); an oracle warps the same stale frame by the true motion (the prediction's error apart from the
affine model's); the error over only the pixels the warp shows, beside the stale frame's on the same pixels.

Cost. In the same Chromium, time per frame of the panel's warp (edges continued; black fill) beside the
thesis's per-pixel algorithm (getImageData, a JavaScript loop that shifts and scales with black fill,
putImageData; in benchmarks/feedback_harness.js, not in the product), interleaved frame by frame at 320x240
and 640x480. Each timed frame ends with a 1-pixel getImageData so that the drawing is finished, not merely
submitted. Chromium runs with --disable-gpu: the canvas is rasterised by Skia on the CPU.
"""

from __future__ import annotations

import argparse
import base64
import functools
import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.report import Measurement, print_table, write_json
from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.world import PHYSICS_DT_S, PHYSICS_STEPS_PER_TICK, World

ROOT = Path(__file__).resolve().parent.parent
STATIC_DIR = ROOT / "client_ui" / "static"
HARNESS = Path(__file__).resolve().parent / "feedback_harness.js"
CHROMIUM_PATH = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]

# The console's default speed (drive pad slider at 50 % of the Telebot's 0.5 m/s and 1.5 rad/s).
MOTIONS: dict[str, tuple[float, float]] = {
    "turn left": (0.0, 0.75),
    "forward": (0.25, 0.0),
    "backward": (-0.25, 0.0),
    "forward + turn left": (0.25, 0.75),
}
TICK_HZ = round(1.0 / (PHYSICS_DT_S * PHYSICS_STEPS_PER_TICK))  # the world's control rate
COMMAND_EVERY_TICKS = TICK_HZ // 20  # 20 Hz, as the console repeats a held command
IDLE_BEFORE_S = 0.5
HOLD_S = 4.0
IDLE_AFTER_S = 1.0
LAST_PRESENT_S = IDLE_BEFORE_S + HOLD_S + 0.5  # the latest present moment graded (0.5 s after release)
FIRST_CAPTURE_S = 0.25
HFOV_DEG = 60.0
SEED = 7
LASER = LaserSpec()


@dataclass
class Capture:
    """A frame the simulator rendered after a tick, with what a frame header carries and the true pose."""

    tick: int
    rgba: np.ndarray
    last_applied_sequence: int
    pose: Pose2D
    laser_ranges_m: tuple[float, ...]


class _QuietHandler(SimpleHTTPRequestHandler):
    extensions_map = {**SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"}

    def end_headers(self) -> None:
        # Cross-origin isolation: performance.now() then ticks in 5 us rather than 100 us steps.
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        super().end_headers()

    def log_message(self, *_args: object) -> None:
        pass


@contextmanager
def static_server() -> Iterator[str]:
    """client_ui/static on a free loopback port, so the product's modules import as in the console."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(STATIC_DIR)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_port}"
    finally:
        server.shutdown()
        server.server_close()


@contextmanager
def harness_page() -> Iterator[Any]:
    """A headless Chromium tab on the static server with the harness loaded (window.feedbackBench)."""
    from playwright.sync_api import sync_playwright

    with static_server() as url, sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM_PATH, args=CHROMIUM_ARGS)
        try:
            page = browser.new_context().new_page()
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            page.goto(f"{url}/lib/")
            page.add_script_tag(content=HARNESS.read_text())
            yield page
            if errors:
                raise RuntimeError(f"JavaScript errors in the harness: {errors}")
        finally:
            browser.close()


def ms_of(tick: int) -> float:
    return tick * 1000.0 / TICK_HZ


def command_at(motion: tuple[float, float], tick: int) -> tuple[float, float] | None:
    """The velocity held at this tick, or None when no key is held."""
    t = tick / TICK_HZ
    return motion if IDLE_BEFORE_S - 1e-9 <= t < IDLE_BEFORE_S + HOLD_S - 1e-9 else None


def scripted_drive(motion: tuple[float, float], render_ticks: set[int],
                   seed: int) -> tuple[dict[int, Capture], list[dict[str, Any]]]:
    """Drives the script tick by tick in fast mode; renders after the ticks asked for, before that tick's send."""
    world = World("lab", seed=seed, realtime=False, deadman_timeout_s=0.4)
    token = "feedback-benchmark"
    world.set_controller(token)
    captures: dict[int, Capture] = {}
    commands: list[dict[str, Any]] = []
    sequence = 0
    held_before = False
    try:
        last_tick = max(render_ticks)
        for tick in range(last_tick + 1):
            if tick in render_ticks:
                snapshot = world.snapshot
                rgba = world.render_rgba().copy()
                rgba[..., 3] = 255
                captures[tick] = Capture(tick, rgba, snapshot.last_applied_sequence, snapshot.ground_truth,
                                         snapshot.laser_ranges_m)
            if tick % COMMAND_EVERY_TICKS == 0:
                held = command_at(motion, tick)
                message: dict[str, Any] | None = None
                if held is not None:
                    sequence += 1
                    message = {"type": "drive", "sequence": sequence, "linear_mps": held[0], "angular_radps": held[1]}
                    world.drive(token, sequence, held[0], held[1])
                elif held_before:  # the key released: one stop, then the repeats end
                    sequence += 1
                    message = {"type": "stop", "sequence": sequence}
                    world.drive(token, sequence, 0.0, 0.0)
                held_before = held is not None
                if message is not None:
                    commands.append({"message": message, "sentMs": ms_of(tick), "tick": tick})
            world.step_for(1.0 / TICK_HZ)
    finally:
        world.stop()
    return captures, commands


def relative_pose(before: Pose2D, after: Pose2D) -> dict[str, float]:
    """The motion from before to after in the robot's frame at before (x ahead, y left)."""
    dx, dy = after.x_m - before.x_m, after.y_m - before.y_m
    cos_t, sin_t = math.cos(before.theta_rad), math.sin(before.theta_rad)
    dtheta = math.atan2(math.sin(after.theta_rad - before.theta_rad), math.cos(after.theta_rad - before.theta_rad))
    return {"x_m": cos_t * dx + sin_t * dy, "y_m": -sin_t * dx + cos_t * dy, "theta_rad": dtheta}


def decode_rgba(b64: str, shape: tuple[int, ...]) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype=np.uint8).reshape(shape)


def mae(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Mean absolute error over every pixel (or those of mask) and RGB channel, 0-255."""
    error = np.abs(a[..., :3].astype(np.int16) - b[..., :3].astype(np.int16))
    if mask is None:
        return float(error.mean())
    return float(error[mask].mean()) if mask.any() else float("nan")


def capture_ticks(delay_s: float, moments: int) -> list[int]:
    """Stale-frame capture ticks, spread so every window [capture, capture + delay] sees motion."""
    last = LAST_PRESENT_S - delay_s
    return sorted({round(t * TICK_HZ) for t in np.linspace(FIRST_CAPTURE_S, last, moments)})


def measure_prediction(page: Any, motions: list[str], delays: list[float], moments: int,
                       quick: bool) -> tuple[list[Measurement], list[dict[str, Any]]]:
    """MAE of the stale and the warped frame against the present one, per motion type and delay."""
    rows: list[Measurement] = []
    details: list[dict[str, Any]] = []
    for index, name in enumerate(motions):
        plan = {delay: capture_ticks(delay, moments) for delay in delays}
        render_ticks = {tick + offset for delay, ticks in plan.items()
                        for tick in ticks for offset in (0, round(delay * TICK_HZ))}
        captures, commands = scripted_drive(MOTIONS[name], render_ticks, SEED + index)
        for delay in delays:
            stale_errors, warped_errors, oracle_errors = [], [], []
            stale_shown, warped_shown, coverage = [], [], []  # over the pixels the warp shows (no black fill)
            black_errors, depths = [], []
            for tick in plan[delay]:
                stale, present = captures[tick], captures[tick + round(delay * TICK_HZ)]
                now_ms = ms_of(present.tick)
                sent = [c for c in commands if c["tick"] < present.tick]  # sent before the present frame's render
                height, width = stale.rgba.shape[:2]
                result = page.evaluate("args => window.feedbackBench.predictWarp(args)", {
                    "stale": base64.b64encode(stale.rgba.tobytes()).decode(), "width": width, "height": height,
                    "hfovDeg": HFOV_DEG, "commands": [{"message": c["message"], "sentMs": c["sentMs"]} for c in sent],
                    "appliedSequence": stale.last_applied_sequence, "nowMs": now_ms,
                    "truePose": relative_pose(stale.pose, present.pose),
                    # The telemetry the console has with this frame (delayed alike): the scan taken with it.
                    "scan": {"angle_min_rad": LASER.angle_min_rad, "angle_increment_rad": LASER.angle_increment_rad,
                             "ranges_m": list(stale.laser_ranges_m)},
                })
                identity = decode_rgba(result["identity"], stale.rgba.shape)
                if mae(identity, stale.rgba) > 0.5:
                    raise RuntimeError("the canvas does not give back the frame it was given (colour management?)")
                warped = decode_rgba(result["warped"], stale.rgba.shape)
                oracle = decode_rgba(result["oracle"], stale.rgba.shape)
                cover = decode_rgba(result["coverage"], stale.rgba.shape)[..., :1].astype(np.float64) / 255.0
                covered = cover[..., 0] >= 1.0
                warped_black = decode_rgba(result["warpedBlack"], stale.rgba.shape)
                black_errors.append(mae(warped_black, present.rgba))
                depths.append(result["depthM"])
                errors = (mae(stale.rgba, present.rgba), mae(warped, present.rgba), mae(oracle, present.rgba))
                stale_errors.append(errors[0])
                warped_errors.append(errors[1])
                oracle_errors.append(errors[2])
                shown = (mae(stale.rgba, present.rgba, covered), mae(warped, present.rgba, covered))
                if covered.any():
                    stale_shown.append(shown[0])
                    warped_shown.append(shown[1])
                coverage.append(float(covered.mean()))
                details.append({
                    "motion": name, "delay_s": delay, "capture_s": tick / TICK_HZ, "present_s": present.tick / TICK_HZ,
                    "last_applied_sequence": stale.last_applied_sequence,
                    "outstanding_commands": result["outstanding"],
                    "mae_stale": errors[0], "mae_warped": errors[1], "mae_oracle": errors[2],
                    "coverage": coverage[-1],
                    "mae_stale_where_shown": shown[0] if covered.any() else None,
                    "mae_warped_where_shown": shown[1] if covered.any() else None,
                    "mae_warped_black_fill": black_errors[-1], "reference_depth_m": depths[-1],
                    "predicted_pose": result["predictedPose"], "true_pose": relative_pose(stale.pose, present.pose),
                    "transform": result["transform"], "oracle_transform": result["oracleTransform"],
                })
            stale_mean = float(np.mean(stale_errors))
            warped_mean = float(np.mean(warped_errors))
            oracle_mean = float(np.mean(oracle_errors))
            ratio = warped_mean / stale_mean if stale_mean > 0 else float("nan")
            better = sum(w < s for w, s in zip(warped_errors, stale_errors, strict=True))
            scenario = f"{name}, {delay:g} s"
            note = f"{len(stale_errors)} moments, warped better at {better}"
            rows += [
                Measurement(scenario, "MAE stale frame vs present", stale_mean, "0-255", "-"),
                Measurement(scenario, "MAE warped frame vs present", warped_mean, "0-255", "< stale", stale_mean,
                            None if quick else warped_mean < stale_mean, note),
                Measurement(scenario, "warped / stale", ratio, "x", "< 1", None, None if quick else ratio < 1),
                Measurement(scenario, "MAE warped by true motion (oracle)", oracle_mean, "0-255", "-"),
            ]
            share = f"the warp shows {100 * float(np.mean(coverage)):.0f} % of the view"
            if warped_shown:
                shown_stale, shown_warped = float(np.mean(stale_shown)), float(np.mean(warped_shown))
                rows.append(Measurement(scenario, "MAE warped where it shows pixels", shown_warped, "0-255",
                                        "-", shown_stale, None, f"floor: stale on the same pixels; {share}"))
            else:
                rows.append(Measurement(scenario, "MAE warped where it shows pixels", None, "0-255", "-", None,
                                        None, share))
            black_mean = float(np.mean(black_errors))
            known = [d for d in depths if d is not None]
            rows.append(Measurement(scenario, "MAE warped, black fill (thesis) vs present", black_mean, "0-255", "-",
                                    stale_mean, None, "the console's other fill choice"))
            rows.append(Measurement(scenario, "depth the zoom assumed (laser median)",
                                    float(np.median(known)) if known else None, "m", "-", None, None,
                                    f"{len(known)} of {len(depths)} moments from the scan"))
    return rows, details


def measure_cost(page: Any, frame: np.ndarray, frames: int, warmup: int,
                 quick: bool) -> tuple[list[Measurement], dict[str, Any]]:
    """ms per frame of the canvas warp and of the per-pixel loop, at 320x240 and 640x480."""
    rows: list[Measurement] = []
    details: dict[str, Any] = {}
    for scale in (1, 2):
        image = np.ascontiguousarray(frame.repeat(scale, axis=0).repeat(scale, axis=1))
        height, width = image.shape[:2]
        result = page.evaluate("args => window.feedbackBench.measureCost(args)", {
            "frame": base64.b64encode(image.tobytes()).decode(), "width": width, "height": height,
            "frames": frames, "warmup": warmup,
        })
        size = f"{width}x{height}"
        details[size] = result
        layer, loop = result["layer"]["median"], result["perPixel"]["median"]
        scenario = f"cost {size}"
        rows += [
            Measurement(scenario, "feedback layer (canvas, edges), median", layer, "ms/frame", "< per-pixel", loop,
                        None if quick else layer < loop,
                        f"p95 {result['layer']['p95']:.2f}, mean {result['layer']['mean']:.2f}"),
            Measurement(scenario, "feedback layer, black fill, median", result["layerBlack"]["median"], "ms/frame", "-",
                        None, None, f"p95 {result['layerBlack']['p95']:.2f}"),
            Measurement(scenario, "thesis per-pixel loop, median", loop, "ms/frame", "-", None, None,
                        f"p95 {result['perPixel']['p95']:.2f}, mean {result['perPixel']['mean']:.2f}"),
            Measurement(scenario, "per-pixel / feedback layer", loop / layer if layer > 0 else float("nan"), "x",
                        "> 1", None, None if quick else loop > layer,
                        f"{frames} frames; outputs differ by MAE {result['agreementMae']:.1f}"),
            Measurement(scenario, "whole panel draw, median", result["panelDraw"]["median"], "ms/frame", "-", None,
                        None, f"FeedbackLayer.draw: predict, warp, path; p95 {result['panelDraw']['p95']:.2f}, "
                        f"mean {result['panelDraw']['mean']:.2f}"),
        ]
    return rows, details


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.feedback", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    args = parser.parse_args(argv)
    quick = args.quick
    motions = ["turn left", "forward"] if quick else list(MOTIONS)
    delays = [1.0] if quick else [1.0, 3.0]
    moments = 3 if quick else 8
    frames, warmup = (50, 5) if quick else (300, 20)
    started = time.monotonic()
    with harness_page() as page:
        prediction_rows, moments_detail = measure_prediction(page, motions, delays, moments, quick)
        world = World("lab", seed=SEED, realtime=False)
        try:
            world.step_for(0.05)
            cost_frame = world.render_rgba().copy()
        finally:
            world.stop()
        cost_frame[..., 3] = 255
        cost_rows, cost_detail = measure_cost(page, cost_frame, frames, warmup, quick)
    rows = prediction_rows + cost_rows
    print_table("camera feedback layer: prediction under delay, and cost per frame in headless Chromium", rows)
    elapsed = time.monotonic() - started
    print(f"\n({'quick' if quick else 'full'} run, {elapsed:.0f} s)")
    write_json(args.output / "feedback.json", rows, {
        "quick": quick, "elapsed_s": elapsed,
        "config": {"motions": {name: MOTIONS[name] for name in motions}, "delays_s": delays,
                   "moments_per_delay": moments, "seed": SEED, "cost_frames": frames, "cost_warmup": warmup,
                   "script_s": {"idle_before": IDLE_BEFORE_S, "hold": HOLD_S, "idle_after": IDLE_AFTER_S}},
        "moments": moments_detail, "cost": cost_detail,
    })
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
