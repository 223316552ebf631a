"""The class-day benchmark's ratios: to 1 worker at the same class size, and to 1 worker carrying each worker's
share of the class (which alone tells work done twice across workers from a worker's efficiency at its load); and the
tutor's wall's rows, each beside its own floor."""

from __future__ import annotations

import pytest

from benchmarks.class_figures import RunFigures, Stretch, WallFigures, rows_for


def figures(workers: int, students: int, cpu_s: float, student_s: float, steady_cpu_s: float) -> RunFigures:
    return RunFigures(workers=workers, students=students, student_s=student_s, cpu_s=cpu_s, idle_cpu_s=0.0,
                      threads_per_worker=30, idle_threads_per_worker=10, transactions=0, idle_transactions=0.0,
                      requests_s=[0.01], idle_requests_s=[0.01], request_errors=0, acks_s=[0.01], drive_floor_s=[0.001],
                      reconnects_s=[1.0], first_consoles_s=[0.05], seats_lost=0, never_in=0, drives_sent=100,
                      superseded=0, restarts_seen=1, errors=[],
                      steady=Stretch(steady_cpu_s, student_s / 2, 0.0, 1000.0))


def test_two_workers_are_compared_with_one_at_the_class_size_and_with_one_carrying_each_ones_share() -> None:
    one = figures(1, 50, cpu_s=50.0, student_s=5000.0, steady_cpu_s=20.0)  # 10 ms per student-second
    alone_at_25 = figures(1, 25, cpu_s=30.0, student_s=2500.0, steady_cpu_s=12.0)  # 12 ms: less busy, less thrifty
    two = figures(2, 50, cpu_s=60.0, student_s=5000.0, steady_cpu_s=24.0)  # 12 ms
    rows = {row.figure: row for row in rows_for(two, one.cpu_per_student_s, True, one.steady.cpu_per_student_s,
                                                alone_at_25)}
    assert rows["web CPU per student-second / 1 worker's"].measured == 1.2
    assert rows["web CPU per student-second / 1 worker's"].passed is False
    assert rows["web CPU per student-second / 1 worker's carrying 25 students (the load of each)"].measured == 1.0
    assert rows["web CPU per student-second before the restart / 1 worker's carrying 25 students"].measured == 1.0


def test_one_worker_has_no_ratio_rows() -> None:
    one = figures(1, 50, cpu_s=50.0, student_s=5000.0, steady_cpu_s=20.0)
    assert not any(row.unit == "ratio" for row in rows_for(one, one.cpu_per_student_s, True))


def test_the_walls_figures_stand_beside_its_own_floors_and_it_must_show_every_students_robot() -> None:
    one = figures(1, 50, cpu_s=50.0, student_s=5000.0, steady_cpu_s=20.0)
    one.wall = WallFigures(per_s=4.8, alone_per_s=5.1, first_open_s=0.05, reconnects_s=[0.4, 1.2], messages=480,
                           restarts_seen=2, robots_shown=50)
    rows = {row.figure: row for row in rows_for(one, one.cpu_per_student_s, True)}
    received = rows["tutor's wall: messages received per second (floor: the wall before the first login)"]
    assert (received.measured, received.floor) == (4.8, 5.1)
    back = rows["tutor's wall: reconnect after the restart, max (floor: its first opening)"]
    assert (back.measured, back.floor) == (pytest.approx(1200.0), pytest.approx(50.0))
    assert rows["tutor's wall: students' robots in its last poses"].passed is True

    one.wall = WallFigures(per_s=0.0, robots_shown=0)  # a wall that never showed anything
    rows = {row.figure: row for row in rows_for(one, one.cpu_per_student_s, True)}
    back = rows["tutor's wall: reconnect after the restart, max (floor: its first opening)"]
    assert (back.measured, back.floor) == (None, None)
    assert rows["tutor's wall: students' robots in its last poses"].passed is False
