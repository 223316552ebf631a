"""A benchmark's quick run for a smoke test, in a process group of its own. However the run ends (done, its time up,
the test's time up), what is left of the group gets SIGTERM, as `telelab up` is stopped, then SIGKILL after a grace:
a benchmark killed alone had left the labs it started (two `telelab up`, ten robots) running for the rest of the
suite, which slowed every test after it."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
GRACE_S = 15.0  # `telelab up` stops its workers and robots on SIGTERM within a few seconds


def run_quick(module: str, output: Path, timeout_s: float = 280.0) -> subprocess.CompletedProcess[str]:
    """`python -m <module> --quick --output <output>` from the repository's root; its outcome and output."""
    return run_in_group([sys.executable, "-m", module, "--quick", "--output", str(output)], timeout_s)


def run_in_group(command: list[str], timeout_s: float) -> subprocess.CompletedProcess[str]:
    """command in a process group of its own, ended whole however the run ends; its outcome and output."""
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        stdout, stderr = process.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        end_group(process)
        stdout, stderr = process.communicate()
        return subprocess.CompletedProcess(process.args, -signal.SIGTERM, stdout,
                                           f"{stderr}\n(the run took over {timeout_s:.0f} s and was stopped)")
    finally:
        end_group(process)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def end_group(leader: subprocess.Popen[str]) -> None:
    """SIGTERM to every process left in leader's group, SIGKILL to those still there GRACE_S later."""
    if not _signal(leader.pid, signal.SIGTERM):
        return
    deadline = time.monotonic() + GRACE_S
    while time.monotonic() < deadline:
        leader.poll()  # reaped, or the group's dead leader would be counted as still there
        if not _signal(leader.pid, 0):
            return
        time.sleep(0.1)
    _signal(leader.pid, signal.SIGKILL)


def _signal(group: int, number: int) -> bool:
    """Whether the group still had a process to signal."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(group, number)
        return True
    return False
