"""The shape every benchmark reports in: rows beside their floor, a printed table, JSON, PNG histograms."""

from __future__ import annotations

import json
import struct
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np


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
