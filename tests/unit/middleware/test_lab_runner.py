"""`telelab up`'s robots: the lab robots in their scene, then one robot per experiment course."""

from __future__ import annotations

import os
import signal
import socket

import pytest

from middleware.lab_runner import LabStopRequested, lab_robots, run_lab, stop_on_termination_signals


def test_the_lab_starts_its_robots_and_one_robot_per_course() -> None:
    robots = lab_robots(2, "lab")
    assert [(r.name, r.scene) for r in robots] == [
        ("lab-1", "lab"), ("lab-2", "lab"), ("course-a", "course-A"), ("course-b", "course-B"),
    ]
    assert all(r.process is None for r in robots)  # described, not started


def test_the_course_robots_can_be_left_out() -> None:
    assert [r.name for r in lab_robots(1, "lab", course_robots=False)] == ["lab-1"]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_a_termination_signal_stops_the_lab_like_ctrl_c_and_a_second_one_cannot_cut_the_stop_short(
    signum: signal.Signals,
) -> None:
    saved = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        stop_on_termination_signals()
        with pytest.raises(LabStopRequested, match=signum.name):
            os.kill(os.getpid(), signum)
        assert signal.getsignal(signum) is signal.SIG_IGN
        os.kill(os.getpid(), signum)  # ignored while the robots are being stopped
    finally:
        for number, handler in saved.items():
            signal.signal(number, handler)


def test_workers_are_one_per_core_on_postgresql_and_one_on_sqlite() -> None:
    from middleware.lab_runner import choose_workers
    from middleware.robots.processes import SkillServerStartError

    assert choose_workers("sqlite:///x.sqlite3", None) == 1
    assert choose_workers("postgresql+psycopg://db/telelab", None) == max(1, os.cpu_count() or 1)
    assert choose_workers("postgresql+psycopg://db/telelab", 3) == 3
    with pytest.raises(SkillServerStartError, match="need PostgreSQL"):
        choose_workers("sqlite:///x.sqlite3", 2)
    with pytest.raises(SkillServerStartError, match="--workers must be between 1 and 64"):
        choose_workers("postgresql+psycopg://db/telelab", 0)


def test_a_lab_whose_port_is_taken_says_so_before_starting_anything(capsys: pytest.CaptureFixture[str]) -> None:
    saved = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGHUP)}
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        try:
            status = run_lab("127.0.0.1", port, robot_count=1, scene="lab", course_robots=False)
        finally:
            for signum, handler in saved.items():
                signal.signal(signum, handler)
    printed = capsys.readouterr()
    assert status == 1
    assert f"Port {port} on 127.0.0.1 is in use" in printed.err and "--port" in printed.err
    assert "skill server" not in printed.out and "Telelab is running" not in printed.out
