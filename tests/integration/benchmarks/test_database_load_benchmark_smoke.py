"""The database-load benchmark runs end to end in quick mode on PostgreSQL: the code before the event bus (from
git history), today's, and today's unable to hear, each with idle consoles (a smoke check of its structure)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.integration.benchmarks.quick_run import run_quick

ROOT = Path(__file__).resolve().parents[3]
pytestmark = pytest.mark.postgres


def test_quick_database_load_benchmark_counts_transactions_before_and_after_the_event_bus(
        tmp_path: Path, postgres_url: str) -> None:
    result = run_quick("benchmarks.database_load", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "database_load.json").read_text())
    assert report["quick"] is True
    rows = report["rows"]
    scenarios = {row["scenario"] for row in rows}
    has_history = subprocess.run(["git", "cat-file", "-e", "163cb08^{commit}"], cwd=ROOT, check=False,
                                 capture_output=True).returncode == 0
    if has_history:
        assert len(scenarios) == 3 and any("before events" in scenario for scenario in scenarios)
    else:  # a shallow clone: the old code cannot be taken from history, and the run says so
        assert len(scenarios) == 2 and "'before' is not measured" in result.stdout
    for row in rows:
        assert row["target"].strip(), row
        if row["figure"] == "channels open through the window":
            assert row["measured"] == 2 * report["users"], row
        if row["figure"] == "transactions/s reaching PostgreSQL (commits + rollbacks)":
            assert row["measured"] > 0, row
            if has_history:
                assert ("before events" in row["scenario"]) == (row["floor"] is None), "before is the others' floor"
    assert all(row["passed"] is None for row in rows), "quick mode grades nothing"
