"""The capacity benchmark runs end to end in quick mode: `telelab up --workers 1` and `--workers 2` on PostgreSQL,
loaded by one asyncio process (a smoke check of its structure: no timings)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.integration.benchmarks.quick_run import run_quick

pytestmark = pytest.mark.postgres


def test_quick_capacity_benchmark_loads_one_and_two_workers_and_reports_their_ratio(tmp_path: Path,
                                                                                     postgres_url: str) -> None:
    result = run_quick("benchmarks.capacity", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "capacity.json").read_text())
    assert report["quick"] is True
    assert {step["workers"] for step in report["steps"]} == {1, 2}
    for step in report["steps"]:
        assert step["requests"] > 0 and step["errors"] == 0 and step["sockets_lost"] == 0, step
        assert step["telemetry_hz"] > 0 and 0 <= step["load_cpu_share"] < 1, step
    rows = {(row["scenario"], row["figure"]): row for row in report["rows"]}
    for workers in ("1 web worker", "2 web workers"):
        assert rows[(f"capacity, {workers}", "users held at p99 <= 100 ms")]["measured"] is not None
        assert rows[(f"capacity, {workers}", "load generator CPU at the users held")]["unit"] == "% of a core"
    assert rows[("capacity, 2 web workers / 1", "users held, ratio")]["target"] == ">= 1.7"
    assert all(row["target"].strip() for row in report["rows"]), "every row names a target, '-' for none"
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
