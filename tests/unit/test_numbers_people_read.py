"""Numbers a person reads are written in the page's language (issue 29): "0,25 m" for a Spanish student, "0.25 m" in
English. An ES module of client_ui/static writes them through lib/i18n.js's fixed() or number(); `.toFixed(` and
`.toPrecision(` write a decimal point whatever the language, so outside lib/i18n.js they appear only on lines that
say why the number is data, not text (a data attribute, a CSS value, a value sent to the server), with a comment
`// data, not text: <why>`. Dates and times follow the page's language too: `toLocale...String([]` (or with no
language) follows the browser's instead, so a module names LANGUAGE or uses dateTime() and time()."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

STATIC = Path(__file__).resolve().parents[2] / "client_ui" / "static"
ALLOWED = {"lib/i18n.js"}  # fixed() itself: toFixed's rounding with the language's decimal sign
POINT_WRITER = re.compile(r"\.to(?:Fixed|Precision)\(|\.toLocale(?:Date|Time)?String\((?:\[\]|undefined)?\s*[,)]")
MARKER = re.compile(r"// data, not text: \S")


def offending_lines(source: str) -> list[tuple[int, str]]:
    """The lines of one module that write a number with a decimal point and do not say it is data."""
    return [(number, line.strip()) for number, line in enumerate(source.splitlines(), start=1)
            if POINT_WRITER.search(line) and not MARKER.search(line)]


def modules() -> list[Path]:
    return sorted(path for path in STATIC.rglob("*.js")
                  if "vendor" not in path.relative_to(STATIC).parts
                  and path.relative_to(STATIC).as_posix() not in ALLOWED)


def test_no_module_writes_a_number_people_read_with_tofixed() -> None:
    found = {path.relative_to(STATIC).as_posix(): lines for path in modules()
             if (lines := offending_lines(path.read_text(encoding="utf-8")))}
    listing = "\n".join(f"client_ui/static/{path}:{number}: {line}" for path, lines in found.items()
                        for number, line in lines)
    assert not found, ("Write these numbers with fixed(value, digits) or number(value) from lib/i18n.js (a decimal "
                       "comma in Spanish), or end the line with `// data, not text: <why>` if code reads it:\n"
                       f"{listing}")


def test_the_scan_sees_the_modules() -> None:
    names = {path.relative_to(STATIC).as_posix() for path in modules()}
    assert "panels/odometry-panel/odometry-panel.js" in names
    assert "lib/i18n.js" not in names
    assert not any(name.startswith("vendor/") or "/vendor/" in name for name in names)


@pytest.mark.parametrize(("source", "flagged"), [
    ('cell.textContent = range.toFixed(2);', True),
    ('label: `${c.t.toFixed(2)} s`', True),
    ('return String(Number(Number(value).toPrecision(4)));', True),
    ('cell.textContent = range.toFixed(2); // data, not text', True),  # the marker says why
    ('this.dataset.nearestM = range.toFixed(3); // data, not text: a data attribute', False),
    ('cell.textContent = fixed(range, 2);', False),
    ('// value.toFixed(digits) is what fixed() replaces', True),
    ('return date.toLocaleTimeString([], { hour: "2-digit" });', True),
    ('return new Date(at).toLocaleString();', True),
    ('return date.toLocaleTimeString(LANGUAGE, { hour: "2-digit" });', False),
])
def test_the_scan_flags_a_tofixed_without_a_reason(source: str, flagged: bool) -> None:
    assert bool(offending_lines(source)) is flagged
