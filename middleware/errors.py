"""Errors as people and API clients see them: sentences for pages, JSON with a stable code for /api."""

from __future__ import annotations

from flask import Flask, Response, jsonify, render_template, request
from flask_wtf.csrf import CSRFError
from werkzeug.exceptions import HTTPException


class ApiError(Exception):
    """An error an API client sees as JSON: a stable code, a sentence, and the offending field."""

    def __init__(self, status: int, code: str, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.status, self.code, self.message, self.field = status, code, message, field

    def to_dict(self) -> dict[str, object]:
        """The JSON body of the error."""
        return {"error": {"code": self.code, "message": self.message, "field": self.field}}


def _wants_json() -> bool:
    return request.path.startswith("/api/") or request.path.startswith("/ws/")


def _error_response(status: int, code: str, title: str, message: str) -> tuple[Response | str, int]:
    if _wants_json():
        return jsonify(ApiError(status, code, message).to_dict()), status
    return render_template("error.html", title=title, message=message), status


def register_error_handlers(app: Flask) -> None:
    """Installs handlers so no error reaches a user as a stack trace or a bare status line."""

    @app.errorhandler(ApiError)
    def _api_error(error: ApiError):  # type: ignore[no-untyped-def]
        return jsonify(error.to_dict()), error.status

    @app.errorhandler(CSRFError)
    def _csrf_error(error: CSRFError):  # type: ignore[no-untyped-def]
        return _error_response(
            400, "csrf_failed", "The form has expired",
            "The form was missing its security token or it had expired. Reload the page and try again.",
        )

    @app.errorhandler(HTTPException)
    def _http_error(error: HTTPException):  # type: ignore[no-untyped-def]
        status = error.code or 500
        messages = {
            403: "You are not allowed to open this page.",
            404: "There is nothing at this address. Check the link or go back to the lab.",
            405: "This address does not accept that kind of request.",
            413: "The request was too large.",
        }
        message = messages.get(status, error.description or "The request could not be handled.")
        return _error_response(status, error.name.lower().replace(" ", "_"), error.name, message)

    @app.errorhandler(Exception)
    def _unexpected(error: Exception):  # type: ignore[no-untyped-def]
        app.logger.exception("Unhandled error on %s", request.path)
        return _error_response(500, "internal_error", "Something went wrong",
                               "Something went wrong on our side. Try again; if it persists, tell your tutor.")
