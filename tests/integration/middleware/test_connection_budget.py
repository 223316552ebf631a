"""The web tier's PostgreSQL connection budget is checked at start against max_connections, by the gunicorn
configuration file both `telelab up` and a web host's bare gunicorn read."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from middleware.config import ConfigError, connection_budget
from middleware.serve import ConnectionBudgetExceeded, check_connection_budget
from tests.conftest import POSTGRES_SERVER_URL, _postgres_admin

ROOT = Path(__file__).resolve().parents[3]


def _max_connections() -> int:
    with _postgres_admin() as admin:
        row = admin.execute("SELECT current_setting('max_connections')::int - "
                            "current_setting('superuser_reserved_connections')::int").fetchone()
    assert row is not None
    return int(row[0])


@pytest.mark.postgres
def test_a_budget_within_max_connections_is_stated_and_one_past_it_is_refused_naming_what_to_change() -> None:
    allowed = _max_connections()
    per_worker = connection_budget({}).per_worker
    fits = allowed // per_worker - 1  # workers, plus one during a rolling restart
    sentence = check_connection_budget(POSTGRES_SERVER_URL, fits, {})
    assert sentence is not None and f"PostgreSQL allows {allowed}" in sentence
    with pytest.raises(ConnectionBudgetExceeded) as refused:
        check_connection_budget(POSTGRES_SERVER_URL, fits, {"TELELAB_WEB_HOSTS": "2"})
    assert "2 web host(s)" in str(refused.value) and "max_connections" in str(refused.value)
    assert "TELELAB_DB_MAX_OVERFLOW" in str(refused.value)


def test_sqlite_has_no_budget_and_a_wrong_setting_is_named() -> None:
    assert check_connection_budget("sqlite:///x.sqlite3", 8, {}) is None
    with pytest.raises(ConfigError, match="TELELAB_DB_POOL_SIZE"):
        connection_budget({"TELELAB_DB_POOL_SIZE": "²"})
    assert connection_budget({"TELELAB_DB_POOL_SIZE": "3", "TELELAB_DB_MAX_OVERFLOW": "0"}).per_worker == 4


@pytest.mark.postgres
def test_a_web_host_s_gunicorn_with_the_shared_configuration_refuses_too_many_workers_before_starting_any(
        tmp_path: Path) -> None:
    workers = _max_connections() // connection_budget({}).per_worker + 1
    env = {**os.environ, "TELELAB_DATABASE_URL": POSTGRES_SERVER_URL, "TELELAB_SECRET_KEY": "budget-test"}
    finished = subprocess.run(
        [sys.executable, "-m", "gunicorn", "-c", "deploy/gunicorn.conf.py", "-w", str(workers), "-b", "127.0.0.1:0",
         "middleware:create_app()"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    assert finished.returncode != 0
    assert "more PostgreSQL connections than the server allows" in finished.stderr, finished.stderr[-2000:]
    assert "Booting worker" not in finished.stderr
