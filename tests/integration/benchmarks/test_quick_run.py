"""A smoke test's benchmark run leaves nothing behind: a run past its time is stopped with every process it started
(a benchmark killed alone had left two labs running for the rest of the suite)."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from tests.integration.benchmarks.quick_run import run_in_group

# A run that starts a child of its own (as a benchmark starts `telelab up`), says its pid, and never ends.
HANGING = ("import subprocess, sys, time;"
           " child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)']);"
           " print(child.pid, flush=True); time.sleep(120)")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat", encoding="ascii") as stat:  # a zombie is gone for the machine's load
        return stat.read().rsplit(")", 1)[1].split()[0] != "Z"


def test_a_run_past_its_time_is_stopped_with_the_processes_it_started(tmp_path: Path) -> None:
    started = time.monotonic()
    result = run_in_group([sys.executable, "-c", HANGING], timeout_s=3)
    child = int(result.stdout.split()[0])
    assert result.returncode != 0 and "was stopped" in result.stderr
    deadline = time.monotonic() + 5
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(child), "the run's own child outlived it"
    assert time.monotonic() - started < 20
