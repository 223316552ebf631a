"""The iCalendar writer (parsed back) and the week view's time zones."""

from __future__ import annotations

from datetime import UTC, date, datetime, timedelta
from zoneinfo import ZoneInfo

from middleware.bookings.ical import CalendarEvent, calendar, escape_text, fold
from middleware.bookings.services import BookingView
from middleware.bookings.week import week_days


def unfold_and_parse(text: str) -> list[tuple[str, str]]:
    """(name;params, value) pairs of an RFC 5545 stream, after unfolding."""
    assert text.endswith("\r\n") and "\n" not in text.replace("\r\n", "")
    lines = text.split("\r\n")[:-1]
    for line in lines:
        assert len(line.encode("utf-8")) <= 75, line
    unfolded: list[str] = []
    for line in lines:
        if line.startswith(" "):
            unfolded[-1] += line[1:]
        else:
            unfolded.append(line)
    return [tuple(line.split(":", 1)) for line in unfolded]


def unescape(value: str) -> str:
    out, i = "", 0
    while i < len(value):
        if value[i] == "\\":
            out += "\n" if value[i + 1] in "nN" else value[i + 1]
            i += 2
        else:
            out += value[i]
            i += 1
    return out


def test_the_calendar_parses_back_with_every_required_property() -> None:
    summary = "Telelab booking: Lab 1; café, with a very long title " + "é" * 60 + " \\ end"
    event = CalendarEvent("booking-7@lab.example", datetime(2031, 3, 3, 9, tzinfo=UTC),
                          datetime(2031, 3, 3, 10, 30, tzinfo=UTC), summary, "line one\nline two")
    text = calendar([event], "Telelab bookings of stud", datetime(2031, 3, 1, 12, 0, 5, tzinfo=UTC))
    props = unfold_and_parse(text)
    names = [name for name, _ in props]
    assert names[0] == "BEGIN" and props[0][1] == "VCALENDAR" and props[-1] == ("END", "VCALENDAR")
    assert ("VERSION", "2.0") in props and "PRODID" in names
    values = dict(props)
    assert values["UID"] == "booking-7@lab.example"
    assert values["DTSTAMP"] == "20310301T120005Z"
    assert values["DTSTART"] == "20310303T090000Z" and values["DTEND"] == "20310303T103000Z"
    assert unescape(values["SUMMARY"]) == summary
    assert unescape(values["DESCRIPTION"]) == "line one\nline two"
    assert any(line.startswith(" ") for line in text.split("\r\n")), "the long summary was folded"


def test_folding_never_splits_a_character_and_escaping_covers_the_specials() -> None:
    folded = fold("SUMMARY:" + "€" * 40)
    pieces = folded.split("\r\n")[:-1]
    assert all(len(p.encode()) <= 75 for p in pieces)
    assert "".join(p[1:] if i else p for i, p in enumerate(pieces)) == "SUMMARY:" + "€" * 40
    assert escape_text("a,b;c\\d\ne") == "a\\,b\\;c\\\\d\\ne"


def view(start: datetime, minutes: int, mine: bool) -> BookingView:
    return BookingView(1, "lab-1", "personal", start, start + timedelta(minutes=minutes), "booked", mine, mine,
                       None, None)


def test_the_week_is_laid_out_in_the_viewers_time_zone() -> None:
    booking = view(datetime(2031, 3, 3, 9, 0, tzinfo=UTC), 60, True)  # 10:00-11:00 in Madrid (UTC+1)
    now = datetime(2031, 3, 1, tzinfo=UTC)
    madrid = week_days(date(2031, 3, 3), ZoneInfo("Europe/Madrid"), [booking], now, all_hours=True)
    mine = [(d.day.isoformat(), s.label) for d in madrid for s in d.slots if s.state == "mine"]
    assert mine == [("2031-03-03", "10:00"), ("2031-03-03", "10:30")]
    utc = week_days(date(2031, 3, 3), ZoneInfo("UTC"), [booking], now, all_hours=True)
    assert [s.label for d in utc for s in d.slots if s.state == "mine"] == ["09:00", "09:30"]
    assert len(madrid[0].slots) == 48 and madrid[0].title == "Mon 03 Mar"


def test_a_daylight_saving_day_has_23_hours_of_slots() -> None:
    days = week_days(date(2031, 3, 24), ZoneInfo("Europe/Madrid"), [], datetime(2031, 3, 1, tzinfo=UTC), True)
    sunday = days[6]
    assert sunday.day == date(2031, 3, 30) and len(sunday.slots) == 46
    assert "02:00" not in [s.label for s in sunday.slots]
