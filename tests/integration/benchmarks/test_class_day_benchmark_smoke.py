"""The class-day benchmark runs end to end in quick mode (a smoke check: it grades nothing, but every student must
get in, drive, see the rolling restart and reconnect with their seat)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.integration.benchmarks.quick_run import run_quick


@pytest.mark.postgres
def test_quick_class_day_drives_through_a_rolling_restart_and_keeps_every_seat(tmp_path: Path) -> None:
    result = run_quick("benchmarks.class_day", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "class_day.json").read_text())
    figures = {row["figure"]: row for row in report["rows"]}
    (run,) = report["runs"]
    assert run["restarts_seen"] >= report["students"], "every console saw its worker leave (1012)"
    assert run["reconnects"] >= report["students"] and run["acks"] > 0, run
    assert figures["seats lost"]["measured"] == 0, run["errors"]
    assert figures["threads per worker, everyone in (floor: idle)"]["measured"] > 0
    assert report["machine"]["cores"] >= 1
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
