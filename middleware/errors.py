"""Errors as people and API clients see them: sentences for pages, JSON with a stable code for /api.

Services raise a `Refused` (or an area's subclass: `BookingRefused`, `InvalidField`, `TimeUp`, ...); routes
let it pass, and the one handler here renders it: `{"error": {"code", "message", "field"}}` with its status
under /api/ and /ws/, the error page with the sentence elsewhere. Every handler ends the request's unit of
work without its changes (middleware/db.py). A form page that shows itself again with the sentence wraps
its action in `unless_refused`, which does the same before answering.
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import UTC, date, datetime
from typing import ClassVar, TypeVar

from babel.dates import format_date, format_datetime
from babel.numbers import format_decimal
from flask import Flask, flash, jsonify, redirect, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import get_locale, gettext  # type: ignore[import-untyped]
from flask_wtf.csrf import CSRFError
from werkzeug.exceptions import HTTPException
from werkzeug.http import HTTP_STATUS_CODES

from middleware.db import discard_changes
from middleware.i18n import N_

T = TypeVar("T")


class Refused(Exception):
    """A request refused: an HTTP status, a stable code, a sentence saying what to do, and the field at fault."""

    keeps_changes: ClassVar[bool] = False  # True: what the request did before the refusal is still committed

    def __init__(self, status: int, code: str, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.status, self.code, self.message, self.field = status, code, message, field

    @property
    def message(self) -> str:
        """The sentence in the request's language. A service says it with gettext (English outside a request);
        where the unit of work has failed (an IntegrityError caught), with lazy_gettext, so the language is looked
        up when the refusal is answered, after the request's changes are discarded."""
        return str(self._message)

    @message.setter
    def message(self, message: str) -> None:
        self._message = message

    def to_dict(self) -> dict[str, object]:
        """The JSON body of the error."""
        return {"error": {"code": self.code, "message": self.message, "field": self.field}}


class ApiError(Refused):
    """A refusal a route raises about the request itself (a body that is not JSON, an unknown robot)."""


def written_number(value: float | None, spec: str = "") -> str:
    """A number as a refusal's sentence writes it: in English as Python writes it (the wording clients and tests
    compare: 3600, 0.5, 1e-06), or by the format spec given ("g", ".0f"), in another language with its decimal sign
    (0,5), rounded as spec rounds, never with a thousands separator (limits and ids read as they are typed)."""
    locale = get_locale()
    if locale is None or locale.language == "en" or value is None or isinstance(value, bool):
        return format(value, spec)
    if spec.startswith(".") and spec.endswith("f"):  # a fixed number of decimals, as the spec says (3,90)
        places = int(spec[1:-1])
        return str(format_decimal(value, "0" + ("." + "0" * places if places else ""), locale=locale))
    if spec:
        value = float(format(value, spec))
    return str(format_decimal(value, locale=locale, group_separator=False, decimal_quantization=False))


def written_date(value: date, english: str, pattern: str) -> str:
    """A date or moment as a sentence writes it: in English by the strftime format english (as before), in another
    language by the CLDR pattern (dd MMM: "04 may"); a moment in its own time zone."""
    locale = get_locale()
    if locale is None or locale.language == "en":
        return value.strftime(english)
    if isinstance(value, datetime):
        return str(format_datetime(value, pattern, tzinfo=value.tzinfo or UTC, locale=locale))
    return str(format_date(value, pattern, locale=locale))


def end_refused_request(refused: Refused) -> None:
    """The request's changes go, unless the refusal keeps them (a test's time ran out: it was submitted)."""
    if not refused.keeps_changes:
        discard_changes()


def unless_refused(action: Callable[[], T], answer: Callable[[Refused], T],
                   about_the_page: tuple[int, ...] = (403, 404)) -> T:
    """action(), or answer(refusal) when it is refused: the form shown again with the sentence, or a redirect
    with it flashed. The request's changes are discarded first. A refusal whose status is about_the_page
    (not allowed here, nothing here) is not the form's to show: it passes on to the error page."""
    try:
        return action()
    except Refused as refused:
        if refused.status in about_the_page:
            raise
        end_refused_request(refused)
        return answer(refused)


def flashed(back: str) -> Callable[[Refused], ResponseReturnValue]:
    """The answer of a form whose refusal is a sentence flashed on the page it goes back to (a warning when
    the refusal kept what was done: a late answer was still submitted)."""
    def answer(refused: Refused) -> ResponseReturnValue:
        flash(refused.message, "warning" if refused.keeps_changes else "error")
        return redirect(back, 303)

    return answer


def wants_json() -> bool:
    """Whether this request's errors are JSON (the API and the sockets' handshakes) rather than a page."""
    return request.path.startswith("/api/") or request.path.startswith("/ws/")


def _error_response(status: int, code: str, title: str, message: str,
                    field: str | None = None) -> ResponseReturnValue:
    if wants_json():
        return jsonify(Refused(status, code, message, field).to_dict()), status
    return render_template("error.html", title=title, message=message), status


# The error page's titles (werkzeug's names of the statuses) in the page's language.
_STATUS_TITLES = {400: N_("Bad Request"), 401: N_("Unauthorized"), 403: N_("Forbidden"), 404: N_("Not Found"),
                  405: N_("Method Not Allowed"), 409: N_("Conflict"), 410: N_("Gone"),
                  413: N_("Request Entity Too Large"), 415: N_("Unsupported Media Type"), 423: N_("Locked"),
                  429: N_("Too Many Requests"), 503: N_("Service Unavailable")}


def _status_title(status: int) -> str:
    if status in _STATUS_TITLES:
        return str(gettext(_STATUS_TITLES[status]))
    return HTTP_STATUS_CODES.get(status, "Refused")


def register_error_handlers(app: Flask) -> None:
    """Installs handlers so no error reaches a user as a stack trace or a bare status line."""

    @app.errorhandler(Refused)
    def _refused(error: Refused) -> ResponseReturnValue:
        end_refused_request(error)
        if wants_json():
            return jsonify(error.to_dict()), error.status
        return render_template("error.html", title=_status_title(error.status), message=error.message), error.status

    @app.errorhandler(CSRFError)
    def _csrf_error(error: CSRFError) -> ResponseReturnValue:
        discard_changes()
        return _error_response(
            400, "csrf_failed", gettext("The form has expired"),
            gettext("The form was missing its security token or it had expired. Reload the page and try again."),
        )

    @app.errorhandler(HTTPException)
    def _http_error(error: HTTPException) -> ResponseReturnValue:
        discard_changes()
        status = error.code or 500
        messages = {
            403: gettext("You are not allowed to open this page."),
            404: gettext("There is nothing at this address. Check the link or go back to the lab."),
            405: gettext("This address does not accept that kind of request."),
            413: gettext("The request was too large."),
        }
        message = messages.get(status, error.description or gettext("The request could not be handled."))
        title = _status_title(status) if status in _STATUS_TITLES else error.name
        return _error_response(status, error.name.lower().replace(" ", "_"), title, message)

    @app.errorhandler(Exception)
    def _unexpected(error: Exception) -> ResponseReturnValue:
        discard_changes()
        app.logger.exception("Unhandled error on %s", request.path)
        return _error_response(500, "internal_error", gettext("Something went wrong"),
                               gettext("Something went wrong on our side. Try again; if it persists, tell your "
                                       "tutor."))
