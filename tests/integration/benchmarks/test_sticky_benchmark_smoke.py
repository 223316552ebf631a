"""The sticky-routing benchmark runs end to end in quick mode (a smoke check: it asserts no timings)."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks import sticky


def test_quick_sticky_benchmark_measures_the_robot_and_the_workers_for_each_worker_count(tmp_path: Path) -> None:
    assert sticky.main(["--quick", "--output", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "sticky.json").read_text())
    assert set(report["measured"]) == {"1", "2", "3"}
    assert all(figures["messages"] > 0 for figures in report["measured"].values()), "every worker relayed frames"
    assert all(row["passed"] is None and row["target"] == "-" for row in report["rows"])
    assert {row["figure"] for row in report["rows"]} >= {"skill server CPU (share of one core)",
                                                          "extra CPU without sticky routing"}
