"""The booking week's free slots that the viewer cannot book, marked 'unavailable' with the reason.

The week page's route calls `viewer_availability(days)`; the rule stays in `services.unbookable_weeks` and
the pure marking in `week.py`.
"""

from __future__ import annotations

from dataclasses import dataclass

from flask_login import current_user

from middleware.bookings.services import unbookable_weeks
from middleware.bookings.week import Day, mark_unbookable, slot_weeks
from middleware.db import get_session


@dataclass(frozen=True)
class WeekAvailability:
    """The week's days with unbookable slots marked, and each distinct reason once (for a note above them)."""

    days: list[Day]
    reasons: list[str]


def viewer_availability(days: list[Day]) -> WeekAvailability:
    """days as the logged-in viewer may book them."""
    if not days or not current_user.is_authenticated:
        return WeekAvailability(days, [])
    weeks = unbookable_weeks(get_session(), current_user, slot_weeks(days))
    marked = mark_unbookable(days, weeks)
    reasons = list(dict.fromkeys(s.unbookable.reason for d in marked for s in d.slots if s.unbookable))
    return WeekAvailability(marked, reasons)
