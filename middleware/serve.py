"""Serving the app: a threaded WSGI server (one thread per connection, so WebSockets do not starve)."""

from __future__ import annotations

import logging

from flask import Flask
from werkzeug.serving import make_server


def serve_forever(app: Flask, host: str, port: int) -> None:
    """Serves app until interrupted (Ctrl-C), then closes the listening socket and the robot links."""
    from middleware.robots.registry import robot_registry

    logging.getLogger("werkzeug").setLevel(logging.WARNING)
    server = make_server(host, port, app, threaded=True)
    try:
        server.serve_forever()
    finally:
        server.server_close()
        robot_registry(app).close()
