"""The feedback benchmark runs end to end in quick mode (a smoke check: it asserts no timings or errors)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e

ROOT = Path(__file__).resolve().parents[3]


def test_quick_feedback_benchmark_prints_a_table_and_writes_json_grading_nothing(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "benchmarks.feedback", "--quick", "--output", str(tmp_path)],
        capture_output=True, text=True, timeout=240, check=False, cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert "turn left, 1 s" in result.stdout and "cost 640x480" in result.stdout
    report = json.loads((tmp_path / "feedback.json").read_text())
    figures = {(row["scenario"], row["figure"]) for row in report["rows"]}
    for motion in ("turn left", "forward"):
        for figure in ("MAE stale frame vs present", "MAE warped frame vs present", "warped / stale",
                       "MAE warped by true motion (oracle)"):
            assert (f"{motion}, 1 s", figure) in figures
    for size in ("320x240", "640x480"):
        for figure in ("feedback layer (canvas, edges), median", "thesis per-pixel loop, median",
                       "per-pixel / feedback layer"):
            assert (f"cost {size}", figure) in figures
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
    assert report["quick"] is True and report["moments"], "each graded moment is recorded"
    # The bookkeeping saw the drive: every moment had commands the stale frame did not show yet.
    assert all(moment["outstanding_commands"] > 0 for moment in report["moments"])
