"""Serving the app: Werkzeug's threaded server (`telelab web`) or gunicorn's threaded workers (`telelab up`).

A request thread serves an HTTP request, or a WebSocket only while its channel's checks run: then the socket is
handed to the process's channel loop (live/loop.py), so an open socket holds no thread."""

from __future__ import annotations

import contextlib
import gc
import logging
import os
import signal
import socket
from pathlib import Path
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
        return _closed_at_the_end(body)

    return app


def _closed_at_the_end(body: Any) -> Any:
    """Yields body and closes it however its sending ends. Werkzeug's server closes the body only after draining
    the request socket, and a browser that resets the connection mid-file (a page left while a module loads) makes
    that draining raise first: the static file's handle was then left to the collector, a ResourceWarning."""
    try:
        yield from body
    finally:
        close = getattr(body, "close", None)
        if close is not None:
            close()


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
        access_coordinator(app).close()
        robot_registry(app).close()


def settle_heap() -> None:
    """Takes what the app built at start (modules, models, templates, routes) out of the collector's reach: a full
    collection then walks only what requests made since. Without it every full collection of a worker walked some
    200 000 objects and paused every request in flight for 100-140 ms, a tail that more workers did not shorten."""
    gc.collect()
    gc.freeze()


GRACEFUL_TIMEOUT_S = 15  # a leaving worker's requests and sockets finish within this
GUNICORN_CONFIG = Path(__file__).resolve().parent.parent / "deploy" / "gunicorn.conf.py"


def serve_with_gunicorn(host: str, port: int, workers: int) -> None:
    """Serves create_app() with gunicorn's threaded workers on one port, until SIGINT or SIGTERM, configured by
    deploy/gunicorn.conf.py (the file a deployment's web hosts use).

    Every worker makes its own app after the fork (connections, listeners and the robot links are per process).
    SIGHUP to this process restarts the workers one at a time (roll_restarts).
    """
    from gunicorn.app.base import Application  # type: ignore[import-untyped]

    class LabServer(Application):
        def load_config(self) -> None:
            self.load_config_from_file(str(GUNICORN_CONFIG))
            self.cfg.set("bind", [f"{host}:{port}"])
            self.cfg.set("workers", workers)

        def load(self) -> Flask:
            from middleware import create_app

            return create_app()

    LabServer().run()


class ConnectionBudgetExceeded(RuntimeError):
    """The web tier could hold more PostgreSQL connections than the server allows; the message says what to change."""


def check_connection_budget(database_url: str, workers: int, env: dict[str, str] | None = None) -> str | None:
    """Refuses (ConnectionBudgetExceeded) a web tier whose workers could hold more connections than PostgreSQL's
    max_connections less its superuser_reserved_connections; the budget as a sentence, or None for SQLite (one
    process). Every web host checks as it starts, each counting every host (TELELAB_WEB_HOSTS)."""
    from sqlalchemy import create_engine, text
    from sqlalchemy.pool import NullPool

    from middleware.config import connection_budget

    if not database_url.startswith("postgresql"):
        return None
    budget = connection_budget(env)
    engine = create_engine(database_url, poolclass=NullPool)
    try:
        with engine.connect() as connection:
            max_connections = int(connection.execute(text("SHOW max_connections")).scalar_one())
            reserved = int(connection.execute(text("SHOW superuser_reserved_connections")).scalar_one())
    finally:
        engine.dispose()
    allowed, needed = max_connections - reserved, budget.needed(workers)
    sentence = (f"{budget.web_hosts} web host(s) x ({workers} workers + 1 during a rolling restart) x "
                f"{budget.per_worker} connections a worker (TELELAB_DB_POOL_SIZE {budget.pool_size} + "
                f"TELELAB_DB_MAX_OVERFLOW {budget.max_overflow} + 1 LISTEN) = {needed}; PostgreSQL allows {allowed} "
                f"(max_connections {max_connections} - superuser_reserved_connections {reserved})")
    if needed > allowed:
        raise ConnectionBudgetExceeded(
            f"The web tier could need more PostgreSQL connections than the server allows: {sentence}. Lower the "
            "workers or TELELAB_DB_MAX_OVERFLOW, or raise max_connections (docs/operator-guide/deployment.md).")
    return sentence


def prepare_master(arbiter: Any) -> None:
    """gunicorn's on_starting hook: the connection budget is checked against PostgreSQL before any worker starts (a
    clear error instead of "too many clients" in some worker under load), and the master restarts workers in turn."""
    from middleware.config import ConfigError

    database_url = os.environ.get("TELELAB_DATABASE_URL", "")
    try:
        sentence = check_connection_budget(database_url, int(arbiter.cfg.workers))
    except (ConnectionBudgetExceeded, ConfigError) as refused:
        raise SystemExit(f"telelab: {refused}") from None
    if sentence is not None:
        logging.getLogger("gunicorn.error").info("PostgreSQL connection budget: %s", sentence)
    roll_restarts(arbiter)


def roll_restarts(arbiter: Any) -> None:
    """gunicorn's on_starting hook: the master becomes a RollingArbiter (gunicorn takes no arbiter class from a
    configuration file, and a deployment's bare `gunicorn -c` must restart the same way as `telelab up`)."""
    from middleware.rolling_restart import RollingArbiter

    arbiter.__class__ = RollingArbiter


def settle_worker(worker: Any) -> None:
    """gunicorn's post_worker_init hook: the worker's start-up heap is settled, SIGTERM drains its channels, and it
    tells the master it serves (one byte in its heartbeat file, which the master reads)."""
    settle_heap()
    _close_channels_when_leaving(worker)
    os.write(worker.tmp.fileno(), b"1")


def leave_worker(_server: Any, worker: Any) -> None:
    """gunicorn's worker_exit hook: waits until the worker's sockets have closed (their messages answered), then lets
    go of the robots. Without the wait the process ended before its closing frames left (clients saw 1006) and
    with chat lines still unstored."""
    from middleware.access.coordinator import access_coordinator
    from middleware.live.loop import wait_for_channels
    from middleware.robots.registry import robot_registry

    wait_for_channels(GRACEFUL_TIMEOUT_S)
    app = getattr(worker, "wsgi", None)
    if not isinstance(app, Flask):
        return  # it never made its app
    with contextlib.suppress(Exception):  # the worker is leaving either way; a failed close must not hide why
        access_coordinator(app).close()
        robot_registry(app).close()


def _close_channels_when_leaving(worker: Any) -> None:
    from middleware.live.loop import drain_channels

    def leave(signum: int, frame: Any) -> None:
        worker.handle_exit(signum, frame)
        drain_channels()

    signal.signal(signal.SIGTERM, leave)
