"""The class-day benchmark runs end to end in quick mode (a smoke check: it grades nothing, but every student must
get in, drive, see the rolling restart and reconnect with their seat, and the tutor's wall must show every student's
robot, before the restart and after it)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.integration.benchmarks.quick_run import run_quick


@pytest.mark.postgres
def test_quick_class_day_keeps_every_seat_and_the_tutors_wall_through_a_rolling_restart(tmp_path: Path) -> None:
    result = run_quick("benchmarks.class_day", tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads((tmp_path / "class_day.json").read_text())
    figures = {row["figure"]: row for row in report["rows"]}
    (run,) = report["runs"]
    assert run["restarts_seen"] >= report["students"], "every console saw its worker leave (1012)"
    assert run["reconnects"] >= report["students"] and run["acks"] > 0, run
    assert figures["seats lost"]["measured"] == 0, run["errors"]
    wall = run["wall"]
    assert wall["messages"] > 0, f"the tutor's wall received no message: {run['errors']}"
    received = figures["tutor's wall: messages received per second (floor: the wall before the first login)"]
    assert received["measured"] > 0 and received["floor"] > 0, received
    assert wall["restarts_seen"] >= 1 and wall["reconnects_s"], f"the wall did not come back after the restart: {wall}"
    assert wall["robots_shown"] == report["students"], f"the wall did not show every student's robot: {wall}"
    assert figures["threads per worker, everyone in (floor: idle)"]["measured"] > 0
    assert report["machine"]["cores"] >= 1
    assert all(row["passed"] is None for row in report["rows"]), "quick mode grades nothing"
