"""What the Makefile's targets do on a fresh clone, read from `make --dry-run` (nothing is installed or run)."""

from __future__ import annotations

import subprocess
from pathlib import Path
from types import SimpleNamespace

from tests import conftest

ROOT = Path(__file__).resolve().parent.parent
VENDOR_LOCK = "client_ui/static/vendor/package-lock.json"


def dry_run(*arguments: str) -> str:
    """The commands `make` would run, as if three.js had never been installed (its lock file newer than the stamp)."""
    # --no-print-directory: under `make test` (MAKELEVEL 1) make would add "Entering/Leaving directory" lines.
    command = ["make", "--no-print-directory", "--dry-run", f"--what-if={VENDOR_LOCK}", *arguments]
    result = subprocess.run(command, cwd=ROOT,
                            capture_output=True, text=True, timeout=60, check=True)
    return result.stdout


def test_make_bench_installs_three_js_chromium_and_nginx_for_the_browser_and_proxy_benchmarks() -> None:
    commands = dry_run("bench")
    assert "npm ci" in commands, commands
    assert "apt-get install -y -qq chromium" in commands, commands
    assert "apt-get install -y -qq nginx" in commands, commands  # sticky and class_day run behind Debian's nginx
    assert commands.rstrip().endswith("telelab bench"), commands


def test_make_test_installs_the_headless_shell_the_browser_tests_run_in() -> None:
    assert "chromium chromium-headless-shell" in dry_run("test")
    assert conftest.CHROMIUM_PATH == "/usr/bin/chromium-headless-shell"


def test_make_test_runs_the_files_in_parallel_processes_with_rays_files_in_one() -> None:
    pytest_line = next(line for line in dry_run("test").splitlines() if " -m pytest" in line)
    assert "--dist loadfile" in pytest_line and " -n " in pytest_line, pytest_line
    config = SimpleNamespace(getvalue={"dist": "loadfile", "tx": ["2*popen"]}.__getitem__)
    scheduler = conftest.pytest_xdist_make_scheduler(config, None)
    assert scheduler._split_scope("tests/integration/farm/test_ray_farm.py::test_a") == scheduler._split_scope(
        "tests/integration/benchmarks/test_farm_benchmark_smoke.py::test_b")
    assert scheduler._split_scope("tests/unit/plans/test_plan_text.py::test_a") == "tests/unit/plans/test_plan_text.py"
    assert scheduler._split_scope("tests/e2e/test_turns.py::test_a") == "tests/e2e/test_turns.py"


def test_make_test_runs_one_process_more_than_the_cores_and_never_more_than_four(monkeypatch) -> None:
    for cores, processes in ((1, 2), (2, 3), (3, 4), (16, 4)):
        monkeypatch.setattr(conftest.os, "sched_getaffinity", lambda _pid, cores=cores: set(range(cores)))
        assert conftest.pytest_xdist_auto_num_workers(SimpleNamespace()) == processes


def test_the_files_that_share_a_process_exist() -> None:
    missing = [path for path in conftest.SAME_PROCESS_FILES if not (ROOT / path).is_file()]
    assert not missing, f"renamed or removed: update tests/conftest.py's SAME_PROCESS_FILES ({missing})"


def test_a_parallel_worker_that_has_finished_is_left_for_the_main_process_to_end() -> None:
    """A worker idles until the whole run ends; the exit watchdog would kill it 60 s after its own last file."""
    import threading

    before = {thread.ident for thread in threading.enumerate()}
    conftest.pytest_unconfigure(SimpleNamespace(workerinput={"workerid": "gw0"}))
    assert not [t.name for t in threading.enumerate() if t.ident not in before and t.name == "exit-watchdog"]
