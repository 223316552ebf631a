"""The skill benchmark's quick mode runs end to end and writes its JSON (figures are not graded here)."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks import skills


def test_quick_benchmark_prints_a_table_and_writes_json(tmp_path: Path, capsys: object) -> None:
    assert skills.main(["--quick", "--output", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "skills.json").read_text())
    scenarios = {row["scenario"] for row in report["rows"]}
    assert report["quick"] and scenarios == {"go_to_goal", "wall_following", "round_trip", "localization",
                                             "localization (wrong guess after driving)",
                                             "round_trip (near obstacles, tracked)",
                                             "go_to_goal (free points, tracked)"}
    assert all(row["passed"] is None for row in report["rows"])
