"""Validation of course fields and of enrolment CSV files; errors name the field."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Mapping
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.errors import written_number
from middleware.i18n import N_
from middleware.validation import decimal_int

COURSE_CODE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,31}$")
TURN_LENGTH_S = (10, 3600)
ALLOWANCE_MIN = (0, 10080)
GRADED_RUN_HOLD_MIN = (5, 240)
MAX_CSV_ROWS = 500
FORMULA_PREFIXES = ("=", "+", "-", "@", "\t", "\r")


def clean_code(value: object) -> str:
    """A course code: 1-32 letters, digits, '.', '_' or '-' (stored upper case)."""
    if not isinstance(value, str) or not COURSE_CODE.fullmatch(value.strip()):
        raise InvalidField("code", gettext("code must be 1 to 32 letters, digits, '.', '_' or '-', such as ROB-101."))
    return value.strip().upper()


def clean_title(value: object) -> str:
    """A course title: 1-200 characters on one line."""
    if not isinstance(value, str) or not value.strip() or len(value.strip()) > 200 or not value.isprintable():
        raise InvalidField("title", gettext("title must be 1 to 200 characters on one line."))
    return value.strip()


def clean_whole(value: object, field: str, bounds: tuple[int, int], unit: str) -> int:
    """A whole number within bounds (inclusive), from JSON or a form field."""
    low, high = bounds
    number = decimal_int(value, low, high)
    if number is None or (isinstance(value, str) and value.strip()[:1] in ("+", "-")):
        raise InvalidField(field, gettext("%(field)s must be a whole number of %(unit)s from %(low)s to %(high)s.",
                                          field=field, unit=gettext(unit), low=written_number(low),
                                          high=written_number(high)))
    return number


@dataclass(frozen=True)
class CourseSettings:
    """Validated course fields; None means 'leave as it is'."""

    title: str | None = None
    turn_length_s: int | None = None
    booking_allowance_min: int | None = None
    graded_run_hold_min: int | None = None
    students_set_velocity: bool | None = None
    students_set_watchdog: bool | None = None


def parse_settings(data: Mapping[str, object]) -> CourseSettings:
    """The settings present in data (form or JSON), each validated."""
    return CourseSettings(
        title=clean_title(data["title"]) if data.get("title") is not None else None,
        turn_length_s=(clean_whole(data["turn_length_s"], "turn_length_s", TURN_LENGTH_S, N_("seconds"))
                       if data.get("turn_length_s") not in (None, "") else None),
        booking_allowance_min=(clean_whole(data["booking_allowance_min"], "booking_allowance_min",
                                           ALLOWANCE_MIN, N_("minutes per week"))
                               if data.get("booking_allowance_min") not in (None, "") else None),
        graded_run_hold_min=(clean_whole(data["graded_run_hold_min"], "graded_run_hold_min", GRADED_RUN_HOLD_MIN,
                                         N_("minutes"))
                             if data.get("graded_run_hold_min") not in (None, "") else None),
        students_set_velocity=clean_flag(data.get("students_set_velocity"), "students_set_velocity"),
        students_set_watchdog=clean_flag(data.get("students_set_watchdog"), "students_set_watchdog"),
    )


FLAG_WORDS = {"yes": True, "true": True, "on": True, "1": True, "no": False, "false": False, "off": False, "0": False}


def clean_flag(value: object, field: str) -> bool | None:
    """A yes/no setting from JSON (true/false) or a form ("yes"/"no"); None when absent."""
    if value is None or value == "":
        return None
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in FLAG_WORDS:
        return FLAG_WORDS[value.strip().lower()]
    raise InvalidField(field, gettext("%(field)s must be yes or no (true or false).", field=field))


@dataclass(frozen=True)
class CsvRow:
    """One data row of an enrolment file: its line number and the username cell as written."""

    line: int
    username: str
    empty: bool


def parse_enrolment_csv(data: bytes) -> list[CsvRow]:
    """The rows of a CSV file whose header has a 'username' column (UTF-8, with or without a BOM)."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InvalidField("file", gettext("The file is not UTF-8 text. Save it as 'CSV UTF-8' and upload it "
                                           "again.")) from None
    if "\x00" in text:
        raise InvalidField("file", gettext("The file is not a text CSV file (it contains NUL bytes)."))
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        rows = list(reader)
    except csv.Error as error:
        raise InvalidField("file", gettext("The file is not valid CSV (%(error)s).", error=error)) from None
    header_index = next((i for i, row in enumerate(rows) if any(cell.strip() for cell in row)), None)
    if header_index is None:
        raise InvalidField("file", gettext("The file is empty. Its first line must be the header 'username'."))
    header = [cell.strip().lower() for cell in rows[header_index]]
    if "username" not in header:
        raise InvalidField("file", gettext("The first line must be a header with a 'username' column (found: "
                                           "%(value)s).", value=', '.join(repr(h) for h in header[:5])))
    column = header.index("username")
    body = rows[header_index + 1:]
    if len(body) > MAX_CSV_ROWS:
        raise InvalidField("file", gettext("The file has %(count)s rows; upload at most %(max_csv_rows)s at a time.",
                                           count=len(body), max_csv_rows=MAX_CSV_ROWS))
    result = []
    for offset, row in enumerate(body):
        cell = row[column].strip() if column < len(row) else ""
        result.append(CsvRow(header_index + 2 + offset, cell[:200], not any(c.strip() for c in row)))
    return result


def csv_safe(value: str) -> str:
    """A cell that a spreadsheet will not run as a formula (CSV injection): a leading quote when needed."""
    return "'" + value if value.startswith(FORMULA_PREFIXES) else value


def report_csv(enrolled: list[str], created: list[tuple[str, str]], refused: list[tuple[int, str, str]]) -> str:
    """The enrolment report as CSV (username, password, outcome, line, reason), every cell formula-safe."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    writer.writerow(["username", "password", "outcome", "line", "reason"])
    for name, password in created:
        writer.writerow([csv_safe(name), csv_safe(password), "created and enrolled", "", ""])
    for name in enrolled:
        writer.writerow([csv_safe(name), "", "enrolled", "", ""])
    for line, value, reason in refused:
        writer.writerow([csv_safe(value), "", "refused", str(line), csv_safe(reason)])
    return out.getvalue()
