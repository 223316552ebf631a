"""How pages write moments: "Mon 23 Nov 2026, 21:10 UTC", never raw ISO 8601 (the `moment` template filter).
In Spanish (the request's language, middleware/i18n.py): "lun 23 nov 2026, 21:10 UTC". And numbers (the `number`
filter): "0.5" in English, "0,5" in Spanish."""

from __future__ import annotations

from datetime import UTC, datetime

from babel.dates import format_datetime

from middleware import i18n
from middleware.errors import written_number

# The same moment in each language's words (CLDR patterns, read by Babel), always in UTC.
MOMENT_PATTERNS = {"es": "EEE d MMM y, HH:mm 'UTC'"}


def moment_words(value: datetime | str | None) -> str:
    """A stored moment (a datetime, naive meaning UTC, or its ISO form) in words; "—" when there is none."""
    if value is None or value == "":
        return "—"
    moment = datetime.fromisoformat(value) if isinstance(value, str) else value
    moment = moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)
    language = i18n.current_language()
    if language in MOMENT_PATTERNS:
        return format_datetime(moment, MOMENT_PATTERNS[language], tzinfo=UTC, locale=language).replace(".", "")
    return moment.strftime("%a %d %b %Y, %H:%M UTC")


def number_words(value: float | None, spec: str = "g") -> str:
    """A number as pages write it, with the page's language's decimal sign and no thousands separator: by spec "g"
    as few digits as it needs ("0.5", "2"; Jinja's '%g'|format in English), ".1f" a fixed count of decimals; "—"
    when there is none."""
    return "—" if value is None else written_number(value, spec)
