"""Serving the app: Werkzeug's threaded server (`telelab web`) or gunicorn's threaded workers (`telelab up`).

A request thread serves an HTTP request, or a WebSocket only while its channel's checks run: then the socket is
handed to the process's channel loop (live/loop.py), so an open socket holds no thread."""

from __future__ import annotations

import contextlib
import gc
import logging
import signal
import socket
from typing import Any

from flask import Flask
from werkzeug.serving import BaseWSGIServer, make_server

from middleware.realtime import WEBSOCKET_ENDED


def quiet_websocket_endings(wsgi_app: Any) -> Any:
    """Stops Werkzeug writing an HTTP response onto a finished WebSocket.

    With flask-sock 0.7 under Werkzeug's server, Werkzeug writes "HTTP/1.1 200 OK" onto the socket
    after the handler returns (miguelgrinberg/flask-sock#20, #77); browsers read it as a broken frame
    and see close code 1006 instead of ours (4401, 4404...). Shutting the socket and raising
    ConnectionError makes Werkzeug treat the request as dropped and write nothing.
    """

    def app(environ: dict[str, Any], start_response: Any) -> Any:
        body = wsgi_app(environ, start_response)
        if "werkzeug.socket" in environ and environ.get(WEBSOCKET_ENDED):  # not a handshake refused over HTTP
            _linger_and_close(environ["werkzeug.socket"])
            raise ConnectionError("WebSocket finished")
        return body

    return app


def _linger_and_close(sock: socket.socket, linger_s: float = 1.0) -> None:
    """Sends FIN, then reads until the peer closes: closing with unread bytes (the client's closing frame)
    would send a reset, and a reset can discard our last messages before the client reads them."""
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_WR)
        sock.settimeout(linger_s)
        while sock.recv(4096):
            pass


def make_threaded_server(app: Flask, host: str, port: int) -> BaseWSGIServer:
    """Werkzeug's threaded server for app, with WebSocket endings made clean."""
    logging.getLogger("werkzeug").setLevel(logging.WARNING)
    return make_server(host, port, quiet_websocket_endings(app), threaded=True)


def serve_forever(app: Flask, host: str, port: int) -> None:
    """Serves app until interrupted (Ctrl-C), then closes the listening socket and the robot links."""
    from middleware.access.coordinator import access_coordinator
    from middleware.robots.registry import robot_registry

    server = make_threaded_server(app, host, port)
    settle_heap()
    try:
        server.serve_forever()
    finally:
        server.server_close()
        access_coordinator(app).stop_ticker()
        robot_registry(app).close()


def settle_heap() -> None:
    """Takes what the app built at start (modules, models, templates, routes) out of the collector's reach: a full
    collection then walks only what requests made since. Without it every full collection of a worker walked some
    200 000 objects and paused every request in flight for 100-140 ms, a tail that more workers did not shorten."""
    gc.collect()
    gc.freeze()


GRACEFUL_TIMEOUT_S = 15  # a leaving worker's requests finish within this; its sockets reconnect elsewhere at once


def serve_with_gunicorn(host: str, port: int, workers: int, threads: int = 200) -> None:
    """Serves create_app() with gunicorn's threaded workers on one port, until SIGINT or SIGTERM.

    Every worker makes its own app after the fork (connections, listeners and the robot links are per process).
    SIGHUP to this process restarts the workers one generation at a time: new ones start, the old ones close
    their WebSockets with 1012 (the browser reconnects to a new worker) and finish their requests.
    """
    from gunicorn.app.base import BaseApplication  # type: ignore[import-untyped]

    options = {"bind": f"{host}:{port}", "workers": workers, "worker_class": "gthread", "threads": threads,
               "graceful_timeout": GRACEFUL_TIMEOUT_S, "timeout": 60, "keepalive": 5,
               "post_worker_init": _settle_worker, "worker_exit": _let_go_of_robots,
               "loglevel": "warning", "proc_name": "telelab"}

    class LabServer(BaseApplication):
        def load_config(self) -> None:
            for key, value in options.items():
                self.cfg.set(key, value)

        def load(self) -> Flask:
            from middleware import create_app

            return create_app()

    LabServer().run()


def _settle_worker(worker: Any) -> None:
    """Once the worker's app is made: its start-up heap is settled, and SIGTERM drains its channels."""
    settle_heap()
    _close_channels_when_leaving(worker)


def _close_channels_when_leaving(worker: Any) -> None:
    from middleware.live.loop import drain_channels

    def leave(signum: int, frame: Any) -> None:
        worker.handle_exit(signum, frame)
        drain_channels()

    signal.signal(signal.SIGTERM, leave)


def _let_go_of_robots(_server: Any, worker: Any) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.robots.registry import robot_registry

    app = worker.wsgi
    with contextlib.suppress(Exception):  # the worker is leaving either way; a failed close must not hide why
        access_coordinator(app).stop_ticker()
        robot_registry(app).close()
