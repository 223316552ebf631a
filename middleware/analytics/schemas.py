"""The analytics' query parameters, checked at the edge: a course id, a window of days, the viewer's UTC offset.
Each wrong value is a 400 invalid_field naming the parameter (never a 500, never a silent default)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, date, datetime, timedelta

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.validation import InvalidInput, decimal_int, within_calendar

DEFAULT_DAYS = 28
MAX_DAYS = 366
MAX_OFFSET_MIN = 14 * 60
REPORTS = ("sessions", "students", "heatmap", "waits", "robots")


@dataclass(frozen=True)
class Window:
    """Whole days from first to last (inclusive) in the viewer's zone (utc_offset_min east of UTC), and the UTC
    instants they span [start, end)."""

    first: date
    last: date
    utc_offset_min: int

    @property
    def offset(self) -> timedelta:
        """The viewer's offset from UTC."""
        return timedelta(minutes=self.utc_offset_min)

    @property
    def start(self) -> datetime:
        """The window's first instant, UTC."""
        return datetime(self.first.year, self.first.month, self.first.day, tzinfo=UTC) - self.offset

    @property
    def end(self) -> datetime:
        """The instant after the window's last day, UTC."""
        return datetime(self.last.year, self.last.month, self.last.day, tzinfo=UTC) + timedelta(days=1) - self.offset

    def to_dict(self) -> dict[str, object]:
        """The window as the API tells it."""
        return {"from": self.first.isoformat(), "to": self.last.isoformat(), "utc_offset_min": self.utc_offset_min,
                "start": self.start.isoformat(), "end": self.end.isoformat()}


def _day(args: Mapping[str, str], name: str) -> date | None:
    raw = args.get(name)
    if raw is None or raw == "":
        return None
    try:
        day = date.fromisoformat(raw) if len(raw) == 10 and raw.isascii() else None
    except ValueError:
        day = None
    if day is None or not within_calendar(day):
        raise InvalidInput(name, gettext("%(name)s must be a day written YYYY-MM-DD, such as 2026-11-28.",
                                         name=name))
    return day


def window(args: Mapping[str, str], today: date) -> Window:
    """The window the query asks for: `from` and `to` (YYYY-MM-DD, at most a year apart), by default the last four
    weeks to today; `utc_offset_min` (minutes east of UTC, -840 to 840) places days and hours in the viewer's zone."""
    raw_offset = args.get("utc_offset_min")
    offset = 0
    if raw_offset not in (None, ""):
        parsed = decimal_int(raw_offset, -MAX_OFFSET_MIN, MAX_OFFSET_MIN) if len(str(raw_offset)) <= 8 else None
        if parsed is None:
            raise InvalidInput("utc_offset_min", gettext(
                "utc_offset_min must be a whole number of minutes from -840 to 840."))
        offset = parsed
    last = _day(args, "to") or today
    first = _day(args, "from") or last - timedelta(days=DEFAULT_DAYS - 1)
    if first > last:
        raise InvalidInput("from", gettext("from must not be after to."))
    if (last - first).days + 1 > MAX_DAYS:
        raise InvalidInput("from", gettext("The window may span at most %(days)s days.", days=MAX_DAYS))
    return Window(first, last, offset)


def course_id(args: Mapping[str, str]) -> int | None:
    """The course the query names (`course_id`, a positive whole number), or None for every course the viewer sees."""
    raw = args.get("course_id")
    if raw in (None, "", "all"):
        return None
    parsed = decimal_int(raw, 1, 2**63 - 1) if len(str(raw)) <= 20 else None
    if parsed is None:
        raise InvalidInput("course_id", gettext("course_id must be the number of a course."))
    return parsed


def report(name: str) -> str:
    """A CSV report's name, one of REPORTS."""
    if name not in REPORTS:
        raise InvalidInput("report", gettext("report must be one of: %(names)s.", names=", ".join(REPORTS)))
    return name
