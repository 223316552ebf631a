"""The browser-drawn view's benchmark runs end to end in quick mode (a smoke check: it asserts the report's shape,
never a timing): server CPU per watched robot for each viewer, idle and driven, what each view adds above the
unwatched robot, the browser's frame times, and a pose's capture to glass beside the JPEG camera's."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.feedback import STATIC_DIR
from tests.integration.benchmarks.quick_run import run_quick

GRADED = ("server CPU, drawn view / JPEG camera", "marginal server CPU, drawn view / JPEG camera")


def test_quick_browser_view_benchmark_reports_both_viewers_and_the_frame_times(tmp_path: Path) -> None:
    if not (STATIC_DIR / "vendor/node_modules/three/build/three.module.js").exists():
        pytest.fail("three.js is not installed: `make test` (or `make three`) runs npm ci in client_ui/static/vendor.")
    # A process of its own: the suite's browser (sync Playwright, session-wide) runs an event loop in this thread.
    result = run_quick("benchmarks.browser_view", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "browser_view.json").read_text())
    assert report["quick"] is True
    assert set(report["measured"]) == {"idle", "driven"}
    for state in report["measured"].values():
        assert set(state) == {"none", "drawn", "camera"}
        assert all(set(figures) == {"robot", "worker", "server"} for figures in state.values())
        assert state["none"]["worker"] == 0.0  # nobody watching: no worker relays anything
    assert len(report["frame_times_ms"]["draw"]) == report["frames"] == len(report["frame_times_ms"]["whole"])
    assert report["webgl_renderer"]

    rows = report["rows"]
    assert all(isinstance(row["target"], str) and row["target"] for row in rows), "every target is a string, '-'"
    assert all(row["passed"] is None for row in rows), "a quick run grades nothing"
    ratios = [row for row in rows if row["figure"] in GRADED]
    for figure in GRADED:
        assert [row["scenario"] for row in ratios if row["figure"] == figure] == [
            "one robot, idle, one viewer", "one robot, driven, one viewer"]
    assert all(row["target"] == "<= 1/8" and row["unit"] == "ratio" for row in ratios)
    marginal = [row for row in rows if row["figure"].startswith("marginal server CPU,") and row["unit"] == "cores"]
    assert len(marginal) == 4 and all(row["floor"] is not None for row in marginal)
    figures = {row["figure"] for row in rows if row["scenario"].startswith("robot's-eye view 640x480")}
    assert figures == {"frame time, drawing, p50", "frame time, drawing, p99",
                       "frame time, drawn + taken as bitmap, p50", "frame time, drawn + taken as bitmap, p99"}
    glass = {row["figure"]: row for row in rows if row["scenario"] == "a pose to the glass, headless Chromium"}
    assert set(glass) == {f"capture to glass, {name}, p{q}" for name in ("drawn view", "JPEG camera") for q in (50, 99)}
    drawn_p50, video_p50 = glass["capture to glass, drawn view, p50"], glass["capture to glass, JPEG camera, p50"]
    assert drawn_p50["floor"] == video_p50["measured"]
    assert report["capture_to_glass_ms"]["drawn"] and report["capture_to_glass_ms"]["video"]
    assert all(row["target"] == "-" for row in rows if row not in ratios)
