"""How pages write moments: "Mon 23 Nov 2026, 21:10 UTC", never raw ISO 8601 (the `moment` template filter)."""

from __future__ import annotations

from datetime import UTC, datetime


def moment_words(value: datetime | str | None) -> str:
    """A stored moment (a datetime, naive meaning UTC, or its ISO form) in words; "—" when there is none."""
    if value is None or value == "":
        return "—"
    moment = datetime.fromisoformat(value) if isinstance(value, str) else value
    moment = moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)
    return moment.strftime("%a %d %b %Y, %H:%M UTC")
