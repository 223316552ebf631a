"""The recording benchmark runs end to end in quick mode (a smoke check: it asserts no timings, only that every
figure is measured, the on and off blocks alternate, and quick mode grades nothing)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e


def _quick_run(output: Path) -> subprocess.CompletedProcess[str]:
    """`python -m benchmarks.recording_cost --quick` from the repository's root, output under output."""
    command = [sys.executable, "-m", "benchmarks.recording_cost", "--quick", "--output", str(output)]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, check=False,
                          cwd=Path(__file__).resolve().parents[3])


def test_quick_recording_benchmark_measures_every_figure_in_alternating_blocks_grading_nothing(tmp_path: Path) -> None:
    result = _quick_run(tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Recording cost on the live path" in result.stdout
    report = json.loads((tmp_path / "recording_cost.json").read_text())
    rows = {(row["scenario"], row["figure"]): row for row in report["rows"]}
    for latency in ("drive -> ack", "telemetry -> viewer"):
        for figure in ("p50 on / p50 off, median of pairs", "p99 on / p99 off, median of pairs"):
            assert rows[(latency, figure)]["measured"] > 0, (latency, figure)
        assert rows[(f"{latency}, recording on", "p99")]["floor"] > 0
    assert rows[("recording size", "bytes per minute of session (disk)")]["measured"] > 0
    assert rows[("replay page, 3 min", "time to first frame")]["measured"] > 0
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
    states = [block["state"] for block in report["blocks"]]
    assert states == ["off", "on", "on", "off"], "on and off alternate, in one run"
    assert all(block["drives"] > 0 and block["views"] > 0 for block in report["blocks"])
    assert len(report["load_average_per_block"]) == len(states)
    on_cpu = [shares["worker"] for state, shares in report["cpu_parts_s_per_s"] if state == "on"]
    assert on_cpu and all(share > 0 for share in on_cpu)
    assert rows[("recorder's threads in the worker", "CPU a second, recording on (median of blocks)")]["floor"] == 0
    assert ("recording writer child", "CPU a second, recording on (median of blocks)") in rows
    assert ("channel loop (the tap's thread)", "CPU a second, on - off (median of pairs)") in rows
    assert "too few for a 95% interval" in rows[("drive -> ack", "p50 on / p50 off, median of pairs")]["note"]
