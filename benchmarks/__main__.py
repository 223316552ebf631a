"""`python -m benchmarks [--quick] [--output DIR]`: every benchmark, one after the other (`make bench`)."""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
from pathlib import Path

# Each runs in a process of its own, so one benchmark's threads and worlds do not weigh on the next.
BENCHMARKS = ("benchmarks.latency", "benchmarks.skills", "benchmarks.feedback", "benchmarks.farm",
              "benchmarks.consoles", "benchmarks.workers", "benchmarks.sticky",
              "benchmarks.browser_view", "benchmarks.capacity", "benchmarks.database_load",
              "benchmarks.plans", "benchmarks.response_times", "benchmarks.class_wall",
              "benchmarks.recording_cost", "benchmarks.class_day", "benchmarks.exercises")


def main(argv: list[str] | None = None) -> int:
    """Runs each benchmark module that exists; returns non-zero if one of them failed to run."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="short smoke runs that grade nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    args = parser.parse_args(argv)
    failed = []
    for module in BENCHMARKS:
        if importlib.util.find_spec(module) is None:
            continue
        command = [sys.executable, "-m", module, "--output", str(args.output)] + (["--quick"] if args.quick else [])
        print(f"\n=== {module} ===", flush=True)
        if subprocess.run(command, check=False).returncode != 0:
            failed.append(module)
    if failed:
        print(f"\nthese benchmarks failed to run: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
