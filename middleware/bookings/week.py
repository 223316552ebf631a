"""The week calendar of one robot, laid out in the viewer's time zone; pure, so it is easy to test."""

from __future__ import annotations

from dataclasses import dataclass, replace
from datetime import date, datetime, timedelta
from zoneinfo import ZoneInfo

from middleware.bookings.schemas import SLOT_MINUTES, local_midnight
from middleware.bookings.services import BookingView, Unbookable, iso_week_bounds
from middleware.errors import written_date

DAY_HOURS = range(7, 22)  # shown unless the whole day is asked for


@dataclass(frozen=True)
class Slot:
    """One 30-minute cell: its UTC start, its local label, and what holds it."""

    starts_at: datetime
    label: str  # local HH:MM
    state: str  # free | unavailable (free, but not for this viewer) | mine | taken | past
    booking: BookingView | None
    unbookable: Unbookable | None = None  # why, when unavailable

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
        days.append(Day(day, written_date(day, "%a %d %b", "EEE dd MMM"), day == today, slots))
    return days


def slot_weeks(days: list[Day]) -> set[datetime]:
    """The ISO weeks (Monday 00:00 UTC) the days' free slots fall in: the ones whose allowance matters."""
    return {iso_week_bounds(slot.starts_at)[0] for day in days for slot in day.slots if slot.state == "free"}


def mark_unbookable(days: list[Day], weeks: dict[datetime, Unbookable]) -> list[Day]:
    """The days with each free slot of a week the viewer cannot book turned 'unavailable', with the reason."""
    if not weeks:
        return days
    marked = []
    for day in days:
        slots = []
        for slot in day.slots:
            blocked = weeks.get(iso_week_bounds(slot.starts_at)[0]) if slot.state == "free" else None
            slots.append(replace(slot, state="unavailable", unbookable=blocked) if blocked else slot)
        marked.append(replace(day, slots=slots))
    return marked


def form_default_start(monday: date, zone: ZoneInfo, now: datetime) -> datetime:
    """The booking form's suggested start, local: 09:00 on the shown week's Monday, or, when that has passed
    and the week is still running, the next half hour from now (a suggestion in the past is always refused)."""
    suggestion = datetime.combine(monday, datetime.min.time(), tzinfo=zone).replace(hour=9)
    local_now = now.astimezone(zone).replace(second=0, microsecond=0)
    if local_now < suggestion:
        return suggestion
    next_slot = local_now + timedelta(minutes=SLOT_MINUTES - local_now.minute % SLOT_MINUTES)
    week_end = datetime.combine(monday + timedelta(days=7), datetime.min.time(), tzinfo=zone)
    return next_slot if next_slot < week_end else suggestion
