"""The cross-worker events benchmark runs end to end in quick mode on PostgreSQL (a smoke check: no timings)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.integration.benchmarks.quick_run import run_quick

pytestmark = pytest.mark.postgres


def test_quick_workers_benchmark_measures_both_events_across_and_within_a_worker(tmp_path: Path,
                                                                                  postgres_url: str) -> None:
    result = run_quick("benchmarks.workers", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = json.loads((tmp_path / "workers.json").read_text())["rows"]
    assert len(rows) == 4 and all(row["measured"] > 0 and row["floor"] > 0 for row in rows)
    assert all(row["passed"] is None for row in rows), "quick mode grades nothing"
