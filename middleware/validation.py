"""The edge's one validation layer: what any request may carry before a view reads it, and text made safe to show.

- Path ids: every `<int:...>` rule takes only ids the tables' id columns can hold (32 bits); larger ones are
  404, like an unknown id (the database would otherwise raise on them: SQLite past int64, PostgreSQL past
  int32).
- JSON bodies: nested at most MAX_JSON_DEPTH levels; integers within int64; numbers finite; text that UTF-8
  and the databases can hold (no lone surrogate, no NUL). Anything else is a 400 naming the field, whatever
  the view would have done with it, so no view can store it.
- Query strings, urlencoded forms and path arguments: the same text rule.
- Numeric strings and dates: `decimal_int()` (ASCII digits only, bounded; never `str.isdigit()`, which
  accepts '²', nor `int()` on text, which refuses 4 300 digits with a ValueError), `whole_number()` (the same,
  refused naming the field) and `within_calendar()` (years 1900-9000: a week, a time zone or an ISO week away
  still has a date) for the areas' schemas.
- WebSocket messages: `parse_message()` gives each channel a JSON object whose `type` is one it takes, by the
  rules of JSON bodies, or InvalidInput naming the field; the channel answers that message with an error and
  stays open.
- Text that cannot be stored is refused naming its line and column when it has several lines (a plan, a cue
  track), so the writer finds it.
- Showing stored text: what is already stored and cannot be encoded (a lone surrogate kept in a JSON column
  before this layer existed) is shown with U+FFFD in its place by the response's encoding, never a 500.
  Templates escape as always; a view that builds a `Response` itself uses `printable()`.
"""

from __future__ import annotations

import json
import math
import re
from datetime import date, datetime
from typing import Any

from flask import Flask, Response, request
from flask.json.provider import DefaultJSONProvider
from flask_babel import gettext  # type: ignore[import-untyped]
from werkzeug.routing import IntegerConverter, ValidationError

from middleware.errors import Refused, written_number

INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
MAX_ROW_ID = 2**31 - 1  # the tables' ids are INTEGER: 32 bits on PostgreSQL, which refuses a larger operand
MAX_JSON_DEPTH = 32
# Years far enough from 1 and 9999 that a week, a time zone or an ISO week computed from a date never leaves
# the calendar Python can represent.
EARLIEST, LATEST = date(1900, 1, 1), date(9000, 12, 31)
_DECIMAL = re.compile(r"[+-]?[0-9]{1,19}")
_UNSTORABLE = re.compile(r"[\x00\ud800-\udfff]")
_PLACEHOLDER = "\ufffd"


class InvalidInput(Refused):
    """Input no view may receive (400 invalid_field), naming the field."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(400, "invalid_field", message, field)


class BoundedIntConverter(IntegerConverter):
    """`<int:...>` limited to what the id columns hold: a larger id matches no rule (404), like an unknown one."""

    def to_python(self, value: str) -> int:
        if len(value) > 19 or not value.isascii():
            raise ValidationError()
        number = int(value)
        if number > MAX_ROW_ID:
            raise ValidationError()
        return number


def unstorable(text: str) -> bool:
    """Whether text holds a character UTF-8 cannot encode (a lone surrogate) or PostgreSQL cannot store (NUL)."""
    return _UNSTORABLE.search(text) is not None


def unstorable_place(text: str) -> str:
    """Where text's first unstorable character is and what it is, for a sentence: "line 3, column 7: a NUL"
    ("column 7: ..." for one line)."""
    found = _UNSTORABLE.search(text)
    if found is None:
        return ""
    start = found.start()
    line = text.count("\n", 0, start) + 1
    column = start - (text.rfind("\n", 0, start) + 1) + 1
    what = gettext("a NUL") if found.group() == "\x00" else gettext("a lone surrogate")
    if "\n" in text:
        return str(gettext("line %(line)s, column %(column)s: %(what)s", line=line, column=column, what=what))
    return str(gettext("column %(column)s: %(what)s", column=column, what=what))


def refuse_unstorable(field: str, text: str) -> None:
    """InvalidInput naming field and the place of the first character that cannot be stored, if text has one."""
    if unstorable(text):
        raise InvalidInput(field, gettext("%(field)s holds a character that cannot be stored (%(place)s); remove it.",
                                          field=field, place=unstorable_place(text)))


def printable(text: str) -> str:
    """text with every unstorable character replaced by U+FFFD, for showing what is already stored."""
    return _UNSTORABLE.sub(_PLACEHOLDER, text) if unstorable(text) else text


def decimal_int(value: object, low: int = INT64_MIN, high: int = INT64_MAX) -> int | None:
    """The whole number written in value (ASCII digits, optional sign, surrounding spaces) if low <= it <= high,
    else None. An int passes through under the same bounds; booleans and other types are None."""
    if isinstance(value, str):
        text = value.strip()
        value = int(text) if _DECIMAL.fullmatch(text) else None
    if isinstance(value, bool) or not isinstance(value, int):
        return None
    return value if low <= value <= high else None


def whole_number(value: object, field: str, low: int, high: int) -> int:
    """decimal_int(value, low, high), or InvalidInput naming field and the range."""
    number = decimal_int(value, low, high)
    if number is None:
        raise InvalidInput(field, gettext("%(field)s must be a whole number from %(low)s to %(high)s.", field=field,
                                          low=written_number(low), high=written_number(high)))
    return number


def within_calendar(moment: date | datetime) -> bool:
    """Whether moment is far enough from the calendar's edges for the arithmetic the lab does on dates."""
    day = moment.date() if isinstance(moment, datetime) else moment  # a zone's offset is far less than the margin
    return EARLIEST <= day <= LATEST


def _too_deep(what: str = "JSON") -> str:
    depth = written_number(MAX_JSON_DEPTH)
    if what == "message":
        return str(gettext("The message is nested more than %(depth)s levels deep.", depth=depth))
    return str(gettext("The JSON is nested more than %(depth)s levels deep.", depth=depth))


def check_json(value: Any) -> None:
    """Refuses (InvalidInput naming the field) a decoded JSON value a view must never receive."""
    pending: list[tuple[Any, str, int]] = [(value, "body", 0)]
    while pending:
        item, field, depth = pending.pop()
        if depth > MAX_JSON_DEPTH:
            raise InvalidInput(field, _too_deep())
        if isinstance(item, str):
            refuse_unstorable(field, item)
        elif isinstance(item, bool) or item is None:
            continue
        elif isinstance(item, int):
            if not INT64_MIN <= item <= INT64_MAX:
                raise InvalidInput(field, gettext("%(field)s is too large a number.", field=field))
        elif isinstance(item, float):
            if not math.isfinite(item):
                raise InvalidInput(field, gettext("%(field)s must be a finite number.", field=field))
        elif isinstance(item, dict):
            for key, inner in item.items():
                name = key if field == "body" else f"{field}.{key}"
                if not isinstance(key, str) or unstorable(key):
                    raise InvalidInput(field, gettext("A name in %(field)s holds a character that cannot be stored.",
                                                      field=field))
                pending.append((inner, name, depth + 1))
        elif isinstance(item, list):
            pending.extend((inner, f"{field}[{index}]", depth + 1) for index, inner in enumerate(item))


def loads_checked(data: str | bytes) -> Any:
    """json.loads, then check_json; nesting too deep for the parser is refused the same way. A ValueError is
    raised for text that is not JSON (as json.loads does)."""
    try:
        value = json.loads(data)
    except RecursionError:
        raise InvalidInput("body", _too_deep()) from None
    check_json(value)
    return value


def _either(types: tuple[str, ...]) -> str:
    """'drive' or 'stop', in the request's language. Said only when refusing: a message taken says nothing, so the
    channel's many messages never look up the language (nor hold a database connection to learn it)."""
    return str(gettext(" or ")).join(repr(kind) for kind in types)


def parse_message(raw: object, types: tuple[str, ...], max_chars: int) -> dict[str, Any]:
    """A WebSocket text message: a JSON object of at most max_chars characters, checked as a JSON body is, whose
    `type` is one of types; otherwise InvalidInput naming the field ("message", "type" or the one at fault)."""
    if not isinstance(raw, str) or len(raw) > max_chars:
        raise InvalidInput("message", gettext("Send JSON text of at most %(max_chars)s characters.",
                                              max_chars=written_number(max_chars)))
    try:
        message = loads_checked(raw)
    except InvalidInput as refused:  # said of a message, not of a request's JSON
        said = _too_deep("message") if refused.message == _too_deep() else refused.message
        raise InvalidInput("message" if refused.field in (None, "body") else str(refused.field), said) from None
    except ValueError:
        raise InvalidInput("message", gettext('The message is not JSON: send {"type": %(expected)s, ...}.',
                                              expected=_either(types))) from None
    if not isinstance(message, dict):
        raise InvalidInput("message", gettext('The message must be a JSON object: {"type": %(expected)s, ...}.',
                                              expected=_either(types)))
    kind = message.get("type")
    if not isinstance(kind, str) or kind not in types:
        raise InvalidInput("type", gettext("type must be %(expected)s.", expected=_either(types)))
    return message


class CheckedJSONProvider(DefaultJSONProvider):
    """The app's JSON: request bodies (get_json) are read by loads_checked, so no view receives what it refuses."""

    def loads(self, s: str | bytes, **kwargs: Any) -> Any:
        return loads_checked(s)


class TolerantResponse(Response):
    """The response class: a text body (a rendered page, JSON, a download) shows an unencodable character
    as U+FFFD instead of failing to encode."""

    def set_data(self, value: bytes | str) -> None:
        if isinstance(value, str):
            value = printable(value).encode()
        super().set_data(value)


def _check_request_text() -> None:
    """Query strings, urlencoded forms and path arguments: text only that can be stored."""
    sources = [request.args]
    if request.mimetype == "application/x-www-form-urlencoded":
        sources.append(request.form)  # multipart forms are read by their views (uploads raise the size limit)
    for source in sources:
        for name, value in source.items(multi=True):
            field = printable(name)
            refuse_unstorable(field, name)
            refuse_unstorable(field, value)
    check_path_arguments(request.view_args)


def check_path_arguments(arguments: dict[str, Any] | None) -> None:
    """A rule's path arguments (a request's, or a channel's opened on a link): text only that can be stored."""
    for name, value in (arguments or {}).items():
        if isinstance(value, str):
            refuse_unstorable(name, value)


def init_app(app: Flask) -> None:
    """Installs the layer on app; call it before any rule is added (the int converter binds then)."""
    app.url_map.converters["int"] = BoundedIntConverter
    app.json = CheckedJSONProvider(app)
    app.response_class = TolerantResponse
    app.before_request(_check_request_text)
