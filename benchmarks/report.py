"""The shape every benchmark reports in: rows beside their floor, a printed table, JSON, PNG histograms; and
the committed record of runs (benchmarks/results/) with the one table generated from it (benchmarks/RESULTS.md).

`python -m benchmarks.report --record bench-results/ --label "what the run is" --table` copies a run's JSON into
benchmarks/results/<date>-<label>.json and regenerates RESULTS.md; `--table` alone regenerates it.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import re
import struct
import subprocess
import sys
import zlib
from dataclasses import asdict, dataclass, fields
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.__main__ import BENCHMARKS


@dataclass
class Measurement:
    """One figure of one scenario, with its target, the floor it is compared with, and the verdict."""

    scenario: str
    figure: str
    measured: float | None
    unit: str
    target: str
    floor: float | None = None
    passed: bool | None = None  # None: reported only (quick mode, or no target)
    note: str = ""


def percentile_ms(samples_s: list[float], q: float) -> float:
    """The q-th percentile of durations in seconds, in milliseconds."""
    return float(np.percentile(np.asarray(samples_s) * 1000.0, q)) if samples_s else float("nan")


def print_table(title: str, rows: list[Measurement]) -> None:
    """Prints the rows as an aligned table."""
    def show(value: float | None) -> str:
        return "—" if value is None else f"{value:.3f}"

    print(f"\n{title}")
    header = f"{'scenario':28} {'figure':44} {'measured':>10} {'floor':>9} {'target':22} result"
    print(header)
    print("-" * len(header))
    for row in rows:
        verdict = "—" if row.passed is None else ("pass" if row.passed else "MISS")
        print(f"{row.scenario:28} {row.figure + ' [' + row.unit + ']':44} {show(row.measured):>10} "
              f"{show(row.floor):>9} {row.target:22} {verdict}" + (f"  ({row.note})" if row.note else ""))


def write_json(path: Path, rows: list[Measurement], extra: dict[str, object] | None = None) -> None:
    """Writes the rows (and anything extra) as JSON."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"rows": [asdict(r) for r in rows], **(extra or {})}, indent=2, allow_nan=False,
                               default=str))


def write_histogram_png(path: Path, samples_ms: list[float], bins: int = 40,
                        size: tuple[int, int] = (400, 200)) -> None:
    """A bar histogram of samples as a small greyscale PNG (no plotting library needed)."""
    width, height = size
    image = np.full((height, width), 255, dtype=np.uint8)
    if samples_ms:
        counts, _ = np.histogram(samples_ms, bins=bins)
        bar_width = width // bins
        tallest = max(int(counts.max()), 1)
        for index, count in enumerate(counts):
            bar_height = int((height - 10) * count / tallest)
            image[height - bar_height:, index * bar_width:(index + 1) * bar_width - 1] = 60
    raw = b"".join(b"\x00" + image[row].tobytes() for row in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw))
                     + chunk(b"IEND", b""))


# ---- the committed record of runs (benchmarks/results/) and the one table generated from it (RESULTS.md) ----------

HERE = Path(__file__).resolve().parent
RESULTS_DIR = HERE / "results"
RESULTS_TABLE = HERE / "RESULTS.md"
ROW_DEFAULTS: dict[str, object] = {"unit": "", "floor": None, "note": ""}  # skills.json's rows carry none of these


def _number_or_none(value: object) -> float | None:
    """JSON numbers stay; NaN (which a benchmark may print) and anything else become None."""
    return float(value) if isinstance(value, int | float) and not math.isnan(value) else None


def normalize_row(row: dict[str, object]) -> dict[str, object]:
    """A benchmark's row in the recorded shape (Measurement's fields in order): numbers or None."""
    normal = {**ROW_DEFAULTS, **row}
    normal["measured"] = _number_or_none(normal.get("measured"))
    normal["floor"] = _number_or_none(normal["floor"])
    names = [field.name for field in fields(Measurement)]
    return {name: normal.get(name) for name in names} | {k: v for k, v in normal.items() if k not in names}


def record_run(run_dir: Path, label: str, results_dir: Path = RESULTS_DIR, machine: str = "",
               notes: tuple[str, ...] = (), date: str | None = None) -> Path:
    """Copies the graded rows of every benchmark JSON in run_dir (bench-results/) into one record,
    results_dir/<date>-<label>.json, and returns its path. A --quick run grades nothing and is refused."""
    reports = {path.stem: json.loads(path.read_text()) for path in sorted(run_dir.glob("*.json"))}
    reports = {name: report for name, report in reports.items() if isinstance(report, dict) and "rows" in report}
    if not reports:
        raise ValueError(f"no benchmark JSON (latency.json, skills.json, ...) in {run_dir}")
    quick = sorted(name for name, report in reports.items() if report.get("quick"))
    if quick:
        raise ValueError(f"{', '.join(quick)}: a --quick run grades nothing; record full runs only")
    ran = max((run_dir / f"{name}.json").stat().st_mtime for name in reports)
    ran_at = datetime.fromtimestamp(ran, UTC)
    date = datetime.strptime(date, "%Y-%m-%d").date().isoformat() if date else ran_at.date().isoformat()
    slug = re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")
    if not slug:
        raise ValueError("the label needs a letter or a digit")
    path = results_dir / f"{date}-{slug}.json"
    if path.exists():
        raise ValueError(f"{path} exists already; choose another label")
    record = {
        "date": date, "recorded_at": ran_at.isoformat(timespec="seconds"), "label": label,
        "machine": machine or f"{os.cpu_count()} cores, {platform.platform()}",
        "source": f"recorded from {run_dir} by `python -m benchmarks.report --record`" + _commit_note(),
        "notes": list(notes),
        "benchmarks": {name: {
            "quick": False, "partial": bool(report.get("partial")),
            "rows": [normalize_row(row) for row in report["rows"]],
            "context": {key: value for key, value in report.items()
                        if key == "config" or (key not in ("rows", "quick", "partial")
                                               and isinstance(value, str | int | float | None))},
        } for name, report in reports.items()},
    }
    results_dir.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2, allow_nan=False, ensure_ascii=False) + "\n")
    return path


def _commit_note() -> str:
    """', at commit <short hash>' when the run is recorded in a git checkout, else nothing."""
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True, text=True,
                                check=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return f", at commit {commit}" if commit else ""


def load_records(results_dir: Path = RESULTS_DIR) -> list[tuple[str, dict[str, Any]]]:
    """(name, record) for every record, oldest first: by date, then the time of the run where it is known
    (transcribed records have none), then by file name."""
    records = [(path.stem, json.loads(path.read_text())) for path in results_dir.glob("*.json")]
    return sorted(records, key=lambda item: (item[1]["date"], item[1].get("recorded_at") or "", item[0]))


def latest_rows(records: list[tuple[str, dict[str, Any]]]) -> list[tuple[str, dict[str, Any], str]]:
    """(benchmark, row, record name) for each figure of each benchmark, from the latest run that has it.

    A complete run of a benchmark replaces all of that benchmark's earlier figures; a partial one (a run the README
    gave only some figures of) replaces just the figures it has."""
    order = [module.rsplit(".", 1)[-1] for module in BENCHMARKS]
    table: dict[str, dict[tuple[str, str], tuple[dict[str, Any], str]]] = {}
    for name, record in records:
        for benchmark, run in record["benchmarks"].items():
            figures = table.setdefault(benchmark, {})
            if not run.get("partial"):
                figures.clear()
            for row in run["rows"]:
                figures[(row["scenario"], row["figure"])] = (row, name)
    known = sorted(table, key=lambda benchmark: (order.index(benchmark) if benchmark in order else len(order),
                                                  benchmark))
    return [(benchmark, row, name) for benchmark in known for row, name in table[benchmark].values()]


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _figure(value: float | None, value_range: list[float] | None = None) -> str:
    if value is None:
        return f"{value_range[0]:.4g}-{value_range[1]:.4g}" if value_range else "—"
    return f"{value:.4g}"


def render_table(records: list[tuple[str, dict[str, Any]]]) -> str:
    """RESULTS.md: one Markdown table of the latest recorded figures, then the runs they come from."""
    rows = latest_rows(records)
    lines = [
        "Generated by `python -m benchmarks.report --table` from `benchmarks/results/`; do not edit by hand.",
        "",
        "# Benchmark results",
        "",
        "Each figure from the latest recorded run that has it (a run recorded with only some of a benchmark's",
        "figures keeps that benchmark's earlier figures for the rest). The floor is measured in the same run;",
        "`—`: no floor, or reported without a verdict. How to record a run: `benchmarks/README.md`.",
        "",
        "| benchmark | scenario | figure | measured | floor | target | result | run | note |",
        "| --- | --- | --- | ---: | ---: | --- | --- | --- | --- |",
    ]
    for benchmark, row, name in rows:
        figure = f"{row['figure']} [{row['unit']}]" if row["unit"] else row["figure"]
        result = "—" if row["passed"] is None else ("pass" if row["passed"] else "MISS")
        lines.append("| " + " | ".join(_cell(cell) for cell in (
            benchmark, row["scenario"], figure, _figure(row["measured"], row.get("measured_range")),
            _figure(row["floor"]), row["target"], result, name, row["note"])) + " |")
    used = {name for _, _, name in rows}
    lines += ["", "Runs:", ""]
    lines += [f"- `{name}`: {_cell(record['label'])}; {_cell(record['machine'])} ({_cell(record['source'])})"
              for name, record in records if name in used]
    lines += render_history(records)
    return "\n".join(lines) + "\n"


def figure_histories(records: list[tuple[str, dict[str, Any]]]) -> dict[tuple[str, str, str], list[tuple[str, str]]]:
    """(benchmark, scenario, figure with its unit) -> [(date, measured)] of every run that measured it, oldest
    first, for the figures more than one run measured."""
    history: dict[tuple[str, str, str], list[tuple[str, str]]] = {}
    for _name, record in records:
        for benchmark, run in record["benchmarks"].items():
            for row in run["rows"]:
                figure = f"{row['figure']} [{row['unit']}]" if row["unit"] else row["figure"]
                measured = _figure(row["measured"], row.get("measured_range"))
                history.setdefault((benchmark, row["scenario"], figure), []).append((record["date"], measured))
    order = [module.rsplit(".", 1)[-1] for module in BENCHMARKS]
    known = sorted(history, key=lambda key: order.index(key[0]) if key[0] in order else len(order))
    return {key: history[key] for key in known if len(history[key]) > 1}


def render_history(records: list[tuple[str, dict[str, Any]]]) -> list[str]:
    """RESULTS.md's history: each figure more than one run measured, with each run's value and date."""
    lines = ["", "## History", "",
             "Each figure that more than one recorded run measured, every run's value with its date, oldest first",
             "(each record in `benchmarks/results/` says the machine and what changed).", "",
             "| benchmark | scenario | figure | measured (date), oldest first |", "| --- | --- | --- | --- |"]
    for (benchmark, scenario, figure), runs in figure_histories(records).items():
        values = ", ".join(f"{measured} ({date})" for date, measured in runs)
        lines.append("| " + " | ".join(_cell(cell) for cell in (benchmark, scenario, figure, values)) + " |")
    return lines


def main(argv: list[str] | None = None) -> int:
    """`python -m benchmarks.report`: record a run, and/or write the table."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.report",
        description="Record a run's JSON in benchmarks/results/ and render RESULTS.md from the records.")
    parser.add_argument("--record", type=Path, metavar="DIR",
                        help="the run's output folder (bench-results/ by default of every benchmark)")
    parser.add_argument("--label", help="what the run is, e.g. 'after the command path' (names the file)")
    parser.add_argument("--machine", default="", help="the machine and its load (default: cores and platform)")
    parser.add_argument("--note", action="append", default=[], help="a note kept with the record (repeatable)")
    parser.add_argument("--date", help="YYYY-MM-DD (default: the day the run's JSON was written)")
    parser.add_argument("--table", action="store_true", help="write RESULTS.md from the records")
    parser.add_argument("--results", type=Path, default=RESULTS_DIR, help="the records' folder")
    parser.add_argument("--output", type=Path, default=RESULTS_TABLE, help="where --table writes")
    args = parser.parse_args(argv)
    if not args.record and not args.table:
        parser.error("nothing to do: give --record DIR --label TEXT, --table, or both")
    if args.record:
        if not args.label:
            parser.error("--record needs --label")
        try:
            path = record_run(args.record, args.label, args.results, args.machine, tuple(args.note), args.date)
        except ValueError as refusal:
            print(f"not recorded: {refusal}", file=sys.stderr)
            return 1
        print(f"recorded {path}")
    if args.table:
        args.output.write_text(render_table(load_records(args.results)))
        print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
