"""How the session cookie travels: Secure whenever the request came over HTTPS, and which proxies may say so.

Behind a TLS-terminating proxy the app sees plain HTTP; with TELELAB_TRUSTED_PROXIES=N werkzeug's ProxyFix
believes the last N X-Forwarded-For/-Proto/-Host/-Port entries, so request.is_secure and remote_addr (the
login throttle's address) are the client's. Without it those headers are ignored: anyone can send them.
"""

from __future__ import annotations

from collections.abc import Callable

from flask import Flask, has_request_context, request
from flask.sessions import SecureCookieSessionInterface
from werkzeug.middleware.proxy_fix import ProxyFix


class HttpsAwareSessionInterface(SecureCookieSessionInterface):
    """Flask's signed-cookie sessions, marked Secure when configured so or when this request is HTTPS."""

    def get_cookie_secure(self, app: Flask) -> bool:
        """SESSION_COOKIE_SECURE, or whether the request came over HTTPS."""
        return bool(app.config["SESSION_COOKIE_SECURE"]) or (has_request_context() and request.is_secure)

    def get_cookie_samesite(self, app: Flask) -> str | None:
        """SameSite=None over HTTPS when the lab is embedded in an LMS's frame (LTI mode: a platform is registered),
        so the cookie reaches Telelab inside the frame; SESSION_COOKIE_SAMESITE otherwise."""
        embedded: Callable[[Flask], bool] | None = app.extensions.get(_CROSS_SITE_KEY)
        if embedded is not None and has_request_context() and request.is_secure and embedded(app):
            return "None"
        return super().get_cookie_samesite(app)


_CROSS_SITE_KEY = "telelab.cookies.cross_site"


def cross_site_when(app: Flask, embedded: Callable[[Flask], bool]) -> None:
    """Makes the session cookie SameSite=None; Secure over HTTPS whenever embedded(app) (the LTI area's hook)."""
    app.extensions[_CROSS_SITE_KEY] = embedded


def init_app(app: Flask) -> None:
    """Installs the session interface and, when configured, the trust in forwarding proxies."""
    app.session_interface = HttpsAwareSessionInterface()
    proxies = int(app.config["TRUSTED_PROXIES"])
    if proxies:
        app.wsgi_app = ProxyFix(app.wsgi_app, x_for=proxies, x_proto=proxies, x_host=proxies,  # type: ignore[method-assign]
                                x_port=proxies)
