"""The farm benchmark runs end to end in quick mode on both backends (a smoke check: it asserts no timings)."""

from __future__ import annotations

import json
from pathlib import Path

from tests.integration.benchmarks.quick_run import run_quick


def test_quick_farm_benchmark_starts_a_class_on_both_backends_and_grades_nothing(tmp_path: Path) -> None:
    result = run_quick("benchmarks.farm", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "farm.json").read_text())
    figures = {(row["scenario"], row["figure"]): row for row in report["rows"]}
    for backend in ("local", "ray"):
        assert figures[(f"farm start ({backend})", "one robot alone")]["measured"] > 0
        for figure in ("start until SERVING p50", "start until SERVING max",
                       "real-time factor, slowest driven and watched robot", "poses received per watched robot",
                       "CPU share per driven and watched robot, mean", "CPU share per parked robot, mean",
                       "wake: drive -> moving, max of 5", "memory per robot, mean"):
            assert figures[(f"class of 2 ({backend})", figure)]["measured"] > 0, (backend, figure)
    assert ("Ray overhead, class of 2", "start until SERVING max ray/local") in figures
    assert figures[("4 idle robots (local)", "CPU share per robot, mean")]["measured"] > 0
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
