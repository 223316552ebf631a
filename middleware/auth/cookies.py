"""How the session cookie travels: Secure whenever the request came over HTTPS, and which proxies may say so.

Behind a TLS-terminating proxy the app sees plain HTTP; with TELELAB_TRUSTED_PROXIES=N werkzeug's ProxyFix
believes the last N X-Forwarded-For/-Proto/-Host/-Port entries, so request.is_secure and remote_addr (the
login throttle's address) are the client's. Without it those headers are ignored: anyone can send them.
"""

from __future__ import annotations

from flask import Flask, has_request_context, request
from flask.sessions import SecureCookieSessionInterface
from werkzeug.middleware.proxy_fix import ProxyFix


class HttpsAwareSessionInterface(SecureCookieSessionInterface):
    """Flask's signed-cookie sessions, marked Secure when configured so or when this request is HTTPS."""

    def get_cookie_secure(self, app: Flask) -> bool:
        """SESSION_COOKIE_SECURE, or whether the request came over HTTPS."""
        return bool(app.config["SESSION_COOKIE_SECURE"]) or (has_request_context() and request.is_secure)


def init_app(app: Flask) -> None:
    """Installs the session interface and, when configured, the trust in forwarding proxies."""
    app.session_interface = HttpsAwareSessionInterface()
    proxies = int(app.config["TRUSTED_PROXIES"])
    if proxies:
        app.wsgi_app = ProxyFix(app.wsgi_app, x_for=proxies, x_proto=proxies, x_host=proxies,  # type: ignore[method-assign]
                                x_port=proxies)
