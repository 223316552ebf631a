"""The booking form's suggested start is never in the past while the week shown is still running."""

from __future__ import annotations

from datetime import UTC, date, datetime
from zoneinfo import ZoneInfo

import pytest

from middleware.bookings.week import form_default_start

PARIS = ZoneInfo("Europe/Paris")
MONDAY = date(2026, 11, 23)


@pytest.mark.parametrize(("now", "expected"), [
    (datetime(2026, 11, 16, 12, 0, tzinfo=UTC), datetime(2026, 11, 23, 9, 0, tzinfo=PARIS)),    # week ahead
    (datetime(2026, 11, 23, 7, 59, tzinfo=UTC), datetime(2026, 11, 23, 9, 0, tzinfo=PARIS)),    # before 09:00
    (datetime(2026, 11, 25, 13, 10, tzinfo=UTC), datetime(2026, 11, 25, 14, 30, tzinfo=PARIS)),  # Wednesday
    (datetime(2026, 11, 25, 13, 30, tzinfo=UTC), datetime(2026, 11, 25, 15, 0, tzinfo=PARIS)),  # on a boundary
    (datetime(2026, 12, 2, 10, 0, tzinfo=UTC), datetime(2026, 11, 23, 9, 0, tzinfo=PARIS)),     # week over
])
def test_the_suggested_start_is_the_next_half_hour_once_the_week_is_under_way(now, expected) -> None:
    assert form_default_start(MONDAY, PARIS, now) == expected
