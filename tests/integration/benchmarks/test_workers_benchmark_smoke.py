"""The cross-worker events benchmark runs end to end in quick mode on PostgreSQL (a smoke check: no timings)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
pytestmark = pytest.mark.postgres


def test_quick_workers_benchmark_measures_both_events_across_and_within_a_worker(tmp_path: Path,
                                                                                  postgres_url: str) -> None:
    result = subprocess.run([sys.executable, "-m", "benchmarks.workers", "--quick", "--output", str(tmp_path)],
                            capture_output=True, text=True, timeout=300, check=False, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = json.loads((tmp_path / "workers.json").read_text())["rows"]
    assert len(rows) == 4 and all(row["measured"] > 0 and row["floor"] > 0 for row in rows)
    assert all(row["passed"] is None for row in rows), "quick mode grades nothing"
