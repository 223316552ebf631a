"""The latency benchmark runs end to end in quick mode (a smoke check: it asserts no timings)."""

from __future__ import annotations

import json
from pathlib import Path

from tests.integration.benchmarks.quick_run import run_quick


def test_quick_latency_benchmark_prints_a_table_and_writes_json_and_histograms(tmp_path: Path) -> None:
    result = run_quick("benchmarks.latency", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "skill activation (total)" in result.stdout and "fan-out, 10 viewers" in result.stdout
    report = json.loads((tmp_path / "latency.json").read_text())
    figures = {(row["scenario"], row["figure"]) for row in report["rows"]}
    assert ("camera capture -> viewer", "p99") in figures
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
    assert (tmp_path / "latency-camera.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
