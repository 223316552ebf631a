"""The consoles benchmark runs end to end in quick mode against `telelab up --workers 1` (a smoke check: it grades
nothing, but every console it opens must open and stream)."""

from __future__ import annotations

import json
from pathlib import Path

from tests.integration.benchmarks.quick_run import run_quick


def test_quick_consoles_benchmark_opens_every_console_on_one_link_each(tmp_path: Path) -> None:
    result = run_quick("benchmarks.consoles", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "consoles.json").read_text())
    figures = {row["figure"]: row for row in report["rows"]}
    assert figures["consoles open on one worker (one link each)"]["measured"] == report["consoles"]
    subscribed = figures["channels subscribed"]
    assert subscribed["measured"] == float(subscribed["target"].removeprefix("= "))
    assert figures["camera fps at the slowest streaming console (floor: their mean)"]["measured"] > 0
    assert figures["ordinary request errors"]["measured"] == 0
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
