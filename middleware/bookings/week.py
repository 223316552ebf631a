"""The week calendar of one robot, laid out in the viewer's time zone; pure, so it is easy to test."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import date, datetime, timedelta
from zoneinfo import ZoneInfo

from middleware.bookings.schemas import SLOT_MINUTES, local_midnight
from middleware.bookings.services import BookingView

DAY_HOURS = range(7, 22)  # shown unless the whole day is asked for


@dataclass(frozen=True)
class Slot:
    """One 30-minute cell: its UTC start, its local label, and what holds it."""

    starts_at: datetime
    label: str  # local HH:MM
    state: str  # free | mine | taken | past
    booking: BookingView | None

    @property
    def iso(self) -> str:
        """The start as ISO 8601 UTC."""
        return self.starts_at.strftime("%Y-%m-%dT%H:%M:%SZ")


@dataclass(frozen=True)
class Day:
    """One column of the week."""

    day: date
    title: str  # "Mon 23 Nov"
    is_today: bool
    slots: list[Slot]


def week_days(monday: date, zone: ZoneInfo, views: list[BookingView], now: datetime, all_hours: bool) -> list[Day]:
    """Seven days of slots from local midnight to local midnight (23, 24 or 25 hours on DST days)."""
    step = timedelta(minutes=SLOT_MINUTES)
    today = now.astimezone(zone).date()
    days = []
    for offset in range(7):
        day = monday + timedelta(days=offset)
        start, end = local_midnight(day, zone), local_midnight(day + timedelta(days=1), zone)
        slots, moment = [], start
        while moment < end:
            local = moment.astimezone(zone)
            if all_hours or local.hour in DAY_HOURS:
                holder = next((v for v in views if v.starts_at <= moment < v.ends_at), None)
                if holder is not None:
                    state = "mine" if holder.mine else "taken"
                elif moment < now:
                    state = "past"
                else:
                    state = "free"
                slots.append(Slot(moment, local.strftime("%H:%M"), state, holder))
            moment += step
        days.append(Day(day, day.strftime("%a %d %b"), day == today, slots))
    return days
