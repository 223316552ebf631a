"""The class-day benchmark's figures: what a class run measured (the whole run, its steady stretch, the tutor's
wall), the machine it ran on, and the rows each figure is reported in beside its floor."""

from __future__ import annotations

import contextlib
import math
import os
import platform
import statistics
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.report import Measurement, percentile_ms, write_json

RATIO_TARGET = 1.10


@dataclass
class Stretch:
    """What the web tier did in a stretch of a class: its workers' CPU, the student-seconds, PostgreSQL's
    transactions and the consoles' messages (drive commands sent, messages received, requests)."""

    cpu_s: float = 0.0
    student_s: float = 0.0
    transactions: float = 0.0
    messages: float = 0.0

    @property
    def cpu_per_student_s(self) -> float:
        return self.cpu_s / self.student_s if self.student_s else float("nan")


@dataclass
class WallFigures:
    """The tutor's wall in one class: its messages a second in the class and before it (None: none came), its first
    opening and reconnects [s], and the students' robots in its last poses."""

    per_s: float | None = None
    alone_per_s: float | None = None
    first_open_s: float | None = None
    reconnects_s: list[float] = field(default_factory=list)
    messages: int = 0
    restarts_seen: int = 0
    robots_shown: int = 0


@dataclass
class RunFigures:
    workers: int
    students: int
    student_s: float
    cpu_s: float
    idle_cpu_s: float
    threads_per_worker: int
    idle_threads_per_worker: int
    transactions: int
    idle_transactions: float
    requests_s: list[float]
    idle_requests_s: list[float]
    request_errors: int
    acks_s: list[float]
    drive_floor_s: list[float]
    reconnects_s: list[float]
    first_consoles_s: list[float]
    seats_lost: int
    never_in: int
    drives_sent: int
    superseded: int
    restarts_seen: int
    errors: list[str]
    steady: Stretch = field(default_factory=Stretch)
    idle_cpu_per_s: float = 0.0
    messages: int = 0
    wall: WallFigures = field(default_factory=WallFigures)

    @property
    def cpu_per_student_s(self) -> float:
        return self.cpu_s / self.student_s if self.student_s else float("nan")


def machine() -> dict[str, object]:
    """What the machine was."""
    model = ""
    with contextlib.suppress(OSError):
        model = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                      if line.startswith("model name")), "")
    memory_gb = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    return {"cores": os.cpu_count(), "cpu": model, "memory_gb": round(memory_gb, 1), "system": platform.platform(),
            "python": platform.python_version(), "load_average_at_start": os.getloadavg()[0]}


def rows_for(figures: RunFigures, one_worker_cpu: float | None, graded: bool,
             one_worker_steady_cpu: float | None = None, same_load: RunFigures | None = None) -> list[Measurement]:
    scenario = f"{figures.students} students, {figures.workers} worker(s)"
    reconnect_p50 = statistics.median(figures.reconnects_s) if figures.reconnects_s else float("nan")
    ratio = figures.cpu_per_student_s / one_worker_cpu if one_worker_cpu else None
    steady = figures.steady
    steady_ratio = (steady.cpu_per_student_s / one_worker_steady_cpu
                    if one_worker_steady_cpu and not math.isnan(steady.cpu_per_student_s) else None)
    request_p99, ack_p99 = percentile_ms(figures.requests_s, 99), percentile_ms(figures.acks_s, 99)
    rows = [
        Measurement(scenario, "web CPU per student-second (floor: idle workers)", figures.cpu_per_student_s * 1000,
                    "ms", "-", floor=figures.idle_cpu_s / figures.student_s * 1000 if figures.student_s else None),
        Measurement(scenario, "web CPU per student-second, everyone in before the restart (floor: idle workers)",
                    steady.cpu_per_student_s * 1000, "ms", "-", floor=figures.idle_cpu_per_s / figures.students * 1000),
        Measurement(scenario, "web CPU per 1000 messages, everyone in before the restart (drive commands, messages "
                              "received, requests)", steady.cpu_s / steady.messages * 1e6 if steady.messages else None,
                    "ms", "-"),
        Measurement(scenario, "PostgreSQL transactions per student-second, everyone in before the restart",
                    steady.transactions / steady.student_s if steady.student_s else None, "count", "-"),
        Measurement(scenario, "web CPU per student-second of the rest: the logins, the restart and after",
                    (figures.cpu_s - steady.cpu_s) / (figures.student_s - steady.student_s) * 1000
                    if figures.student_s > steady.student_s else None, "ms", "-"),
        Measurement(scenario, "threads per worker, everyone in (floor: idle)", float(figures.threads_per_worker),
                    "count", "-", floor=float(figures.idle_threads_per_worker)),
        Measurement(scenario, "PostgreSQL transactions per student-second (floor: idle)",
                    figures.transactions / figures.student_s if figures.student_s else None, "count", "-",
                    floor=figures.idle_transactions / figures.student_s if figures.student_s else None),
        Measurement(scenario, "ordinary request p99 (floor: nobody in)", request_p99, "ms", "-",
                    floor=percentile_ms(figures.idle_requests_s, 99)),
        Measurement(scenario, "drive acknowledgement p99 (floor: the robot's own gRPC Drive)", ack_p99, "ms", "-",
                    floor=percentile_ms(figures.drive_floor_s, 99)),
        Measurement(scenario, "reconnect after the restart, p50 (floor: a console's first opening)",
                    reconnect_p50 * 1000, "ms", "-",
                    floor=statistics.median(figures.first_consoles_s) * 1000 if figures.first_consoles_s else None),
        Measurement(scenario, "reconnect after the restart, max", max(figures.reconnects_s, default=float("nan"))
                    * 1000, "ms", "-"),
        *_wall_rows(scenario, figures.wall, figures.students, graded),
        Measurement(scenario, "drive commands sent on to the robot per student-second (the rest superseded)",
                    (figures.drives_sent - figures.superseded) / figures.student_s if figures.student_s else None,
                    "count", "-"),
        Measurement(scenario, "drive commands superseded by a newer one waiting (share of those sent)",
                    figures.superseded / figures.drives_sent * 100 if figures.drives_sent else None, "%", "-"),
        Measurement(scenario, "seats lost", float(figures.seats_lost + figures.never_in), "count", "= 0",
                    passed=figures.seats_lost + figures.never_in == 0 if graded else None),
        Measurement(scenario, "ordinary request errors", float(figures.request_errors), "count", "-"),
    ]
    if steady_ratio is not None and figures.workers > 1:
        rows.insert(3, Measurement(scenario, "web CPU per student-second before the restart / 1 worker's",
                                   steady_ratio, "ratio", "-", floor=1.0))
    if same_load is not None and figures.workers > 1:
        rows[2:2] = _same_load_rows(scenario, figures, same_load)
    if ratio is not None and figures.workers > 1:
        rows.insert(1, Measurement(scenario, "web CPU per student-second / 1 worker's", ratio, "ratio",
                                   f"<= {RATIO_TARGET:g}", floor=1.0,
                                   passed=ratio <= RATIO_TARGET if graded else None))
    return rows


def _wall_rows(scenario: str, wall: WallFigures, students: int, graded: bool) -> list[Measurement]:
    """The tutor's wall: what it received, how soon it came back after the restart, and whether it showed the class."""
    def ms(seconds: float | None) -> float | None:
        return None if seconds is None else seconds * 1000

    return [
        Measurement(scenario, "tutor's wall: messages received per second (floor: the wall before the first login)",
                    wall.per_s, "count", "-", floor=wall.alone_per_s),
        Measurement(scenario, "tutor's wall: reconnect after the restart, max (floor: its first opening)",
                    ms(max(wall.reconnects_s, default=None)), "ms", "-", floor=ms(wall.first_open_s)),
        Measurement(scenario, "tutor's wall: students' robots in its last poses", float(wall.robots_shown), "count",
                    f"= {students}", passed=wall.robots_shown == students if graded else None),
    ]


def _same_load_rows(scenario: str, figures: RunFigures, alone: RunFigures) -> list[Measurement]:
    """The workers' CPU per student-second over one worker's carrying as many students as each of them: a worker
    spends less per message the busier it is (one wake-up serves more), so this ratio, not the one at the same class
    size, tells work done twice across workers from a worker's efficiency at its load."""
    rows = [Measurement(scenario, f"web CPU per student-second / 1 worker's carrying {alone.students} students "
                                  "(the load of each)", figures.cpu_per_student_s / alone.cpu_per_student_s
                        if alone.cpu_per_student_s else None, "ratio", "-", floor=1.0)]
    if not math.isnan(figures.steady.cpu_per_student_s) and not math.isnan(alone.steady.cpu_per_student_s):
        rows.append(Measurement(scenario, f"web CPU per student-second before the restart / 1 worker's carrying "
                                          f"{alone.students} students", figures.steady.cpu_per_student_s
                                / alone.steady.cpu_per_student_s, "ratio", "-", floor=1.0))
    return rows


def write_figures(output: Path, rows: list[Measurement], extra: dict[str, object]) -> None:
    for row in rows:  # a figure with no sample (no reconnect in a run) is absent, not NaN
        if row.measured is not None and math.isnan(row.measured):
            row.measured = None
        if row.floor is not None and math.isnan(row.floor):
            row.floor = None
    write_json(output / "class_day.json", rows, extra)
