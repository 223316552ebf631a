"""The exercise page's numbers and counts as a person reads them, in English and Spanish (the page's own modules, run in
node): a small negative that rounds to zero reads "0.00 m", never "-0.00 m" (lib/i18n.js fixed(), shared by every
page); a count of floor cells agrees with its noun ("1 cell", "2 cells"; "1 casilla", "0 casillas"), in the grade
table's value and bar alike."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

STATIC = Path(__file__).resolve().parents[3] / "client_ui" / "static"
# The page's <html lang> names the language; i18n.js reads it when it loads, so each language runs in its own node.
HARNESS = """
globalThis.document = { documentElement: { lang: process.argv[1] } };
const { fixed } = await import(process.argv[2] + "/lib/i18n.js");
const { measurementRow, cellsText } = await import(process.argv[2] + "/pages/exercises/measurements.js");
const cells = (value, bar) => measurementRow({ name: "floor cells visited", value, bar, unit: "cells", fraction: 0.5 });
console.log(JSON.stringify({
  fixed: [fixed(-0.001, 2), fixed(-0.004, 2), fixed(-0.04, 1), fixed(-0.4, 0), fixed(-0, 2), fixed(-0.01, 2),
          fixed(-1.25, 2), fixed(0.25, 2)],
  distance: measurementRow({ name: "distance driven", value: -0.002, bar: 6, unit: "m", fraction: 0 }),
  cells: [cells(1, 14), cells(2, 1), cells(0, 14), cells(0.6, 14)],
  counts: [cellsText(1), cellsText(21), cellsText(1000)],
}));
"""


def page_words(language: str) -> dict[str, list]:
    node = shutil.which("node")
    if node is None:
        pytest.fail("node is not installed; make test installs it with the vendor libraries")
    answer = subprocess.run([node, "--input-type=module", "-e", HARNESS, language, STATIC.as_uri()],
                            capture_output=True, text=True, timeout=60, check=True)
    return json.loads(answer.stdout)


def test_english_reads_zero_without_a_sign_and_counts_cells_in_agreement() -> None:
    words = page_words("en")
    assert words["fixed"] == ["0.00", "0.00", "0.0", "0", "0.00", "-0.01", "-1.25", "0.25"]
    assert words["distance"][1] == "0.00 m"
    assert [row[1:3] for row in words["cells"]] == [["1 cell", "≥ 14 cells"], ["2 cells", "≥ 1 cell"],
                                                     ["0 cells", "≥ 14 cells"], ["1 cell", "≥ 14 cells"]]
    assert words["counts"] == ["1 cell", "21 cells", "1,000 cells"]


def test_spanish_reads_zero_without_a_sign_with_a_comma_and_counts_casillas_in_agreement() -> None:
    words = page_words("es")
    assert words["fixed"] == ["0,00", "0,00", "0,0", "0", "0,00", "-0,01", "-1,25", "0,25"]
    assert words["distance"][1] == "0,00 m"
    assert [row[1:3] for row in words["cells"]] == [["1 casilla", "≥ 14 casillas"], ["2 casillas", "≥ 1 casilla"],
                                                     ["0 casillas", "≥ 14 casillas"], ["1 casilla", "≥ 14 casillas"]]
    assert words["counts"][:2] == ["1 casilla", "21 casillas"]
