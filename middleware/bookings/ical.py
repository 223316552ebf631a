"""A small RFC 5545 writer for booking calendars (no iCalendar library is installed).

Lines end in CRLF and are folded at 75 octets without splitting a UTF-8 character; TEXT values
escape backslash, semicolon, comma and newlines; times are UTC with a 'Z'.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime

MAX_LINE_OCTETS = 75


@dataclass(frozen=True)
class CalendarEvent:
    """One VEVENT."""

    uid: str
    starts_at: datetime
    ends_at: datetime
    summary: str
    description: str = ""
    status: str = "CONFIRMED"  # or CANCELLED


def escape_text(value: str) -> str:
    """A TEXT property value (RFC 5545 §3.3.11)."""
    value = value.replace("\\", "\\\\").replace(";", "\\;").replace(",", "\\,")
    return value.replace("\r\n", "\\n").replace("\n", "\\n").replace("\r", "\\n")


def utc_stamp(moment: datetime) -> str:
    """A DATE-TIME in UTC form: 20261123T090000Z."""
    moment = moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)
    return moment.strftime("%Y%m%dT%H%M%SZ")


def fold(line: str) -> str:
    """The content line folded into CRLF-separated pieces of at most 75 octets (continuations start with a space)."""
    pieces: list[str] = []
    current, size, limit = "", 0, MAX_LINE_OCTETS
    for char in line:
        octets = len(char.encode("utf-8"))
        if size + octets > limit:
            pieces.append(current)
            current, size, limit = " ", 1, MAX_LINE_OCTETS
        current += char
        size += octets
    pieces.append(current)
    return "\r\n".join(pieces) + "\r\n"


def calendar(events: Iterable[CalendarEvent], name: str, now: datetime) -> str:
    """A VCALENDAR with one VEVENT per event."""
    lines = ["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//Telelab//Bookings//EN", "CALSCALE:GREGORIAN",
             "METHOD:PUBLISH", f"X-WR-CALNAME:{escape_text(name)}"]
    stamp = utc_stamp(now)
    for event in events:
        lines += ["BEGIN:VEVENT", f"UID:{event.uid}", f"DTSTAMP:{stamp}", f"DTSTART:{utc_stamp(event.starts_at)}",
                  f"DTEND:{utc_stamp(event.ends_at)}", f"SUMMARY:{escape_text(event.summary)}"]
        if event.description:
            lines.append(f"DESCRIPTION:{escape_text(event.description)}")
        lines += [f"STATUS:{event.status}", "END:VEVENT"]
    lines.append("END:VCALENDAR")
    return "".join(fold(line) for line in lines)
