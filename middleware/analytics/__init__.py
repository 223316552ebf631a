"""Usage analytics for tutors and admins, and xAPI statements to an LMS's Learning Record Store; see README.md."""

from __future__ import annotations

from flask import Flask

from middleware.analytics import settings as xapi_settings
from middleware.analytics.outbox import XapiSender

_KEY = "telelab.analytics"


class Analytics:
    """The app's analytics parts: the xAPI settings and the sender (made on first use: tests configure the app
    after create_app)."""

    def __init__(self, app: Flask) -> None:
        self._app = app
        self._sender: XapiSender | None = None

    @property
    def sender(self) -> XapiSender:
        """The sender (made once; it runs only where an LRS is configured)."""
        if self._sender is None:
            self._sender = XapiSender(self._app, xapi_settings.load(self._app))
        return self._sender

    def stop(self) -> None:
        """Stops the sender (tests, shut-down)."""
        if self._sender is not None:
            self._sender.stop()


def init_app(app: Flask) -> None:
    """Starts the xAPI sender with the first request when an LRS is configured (every worker; the elected sends)."""
    xapi_settings.load(app)  # a wrong TELELAB_XAPI_* setting stops the start with a sentence naming it
    analytics = app.extensions[_KEY] = Analytics(app)

    @app.before_request
    def _start_sender() -> None:
        analytics.sender.start()


def analytics_of(app: Flask) -> Analytics:
    """The app's analytics parts."""
    return app.extensions[_KEY]
