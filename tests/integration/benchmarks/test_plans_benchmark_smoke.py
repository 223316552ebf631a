"""The plans benchmark runs end to end in quick mode (a smoke check: it asserts no timings)."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks import plans


def test_quick_plans_benchmark_measures_step_starts_and_both_ways_of_running_steps(tmp_path: Path) -> None:
    assert plans.main(["--quick", "--output", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "plans.json").read_text())
    assert report["steps"] == 20
    measured = report["measured"]
    assert len(measured["step_started_ms"]) == 20 and len(measured["activate_accepted_ms"]) == 20
    assert measured["plan"]["ticks"] > 0 and measured["direct"]["sim_s"] > 0
    assert all(row["passed"] is None and row["target"] for row in report["rows"])
    figures = {(row["scenario"], row["figure"]) for row in report["rows"]}
    assert ("plan step -> skill started", "p99") in figures
    assert {figure for _, figure in figures} >= {"plan / direct, wall time per step",
                                                 "plan / direct, overhead per step in sim time"}
