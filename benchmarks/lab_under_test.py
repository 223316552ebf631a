"""A whole lab on loopback for the benchmarks: a skill server process, the middleware, and a floor app."""

from __future__ import annotations

import json
import re
import secrets
import tempfile
import threading
import time
from http.cookiejar import CookieJar
from pathlib import Path
from unittest import mock
from urllib.parse import urlencode
from urllib.request import HTTPCookieProcessor, HTTPRedirectHandler, Request, build_opener

import grpc
import simple_websocket
from flask import Flask
from flask_sock import Sock

from middleware import create_app
from middleware.auth import services
from middleware.auth.services import create_user
from middleware.config import parse_robots
from middleware.db import session_factory, upgrade_to_head
from middleware.robots.processes import SkillServerProcess, wait_until_serving
from middleware.serve import make_threaded_server
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

PASSWORD = "benchmark-password"
CSRF_FIELD = re.compile(r'name="csrf_token"[^>]*value="([^"]+)"')


class _NoRedirect(HTTPRedirectHandler):
    def redirect_request(self, *_args, **_kwargs):
        return None


class Served:
    """A WSGI app on a free loopback port, in a background thread."""

    def __init__(self, app: Flask) -> None:
        self.server = make_threaded_server(app, "127.0.0.1", 0)
        self.port = self.server.server_port
        self.url = f"http://127.0.0.1:{self.port}"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def stop(self) -> None:
        """Stops serving."""
        self.server.shutdown()
        self.server.server_close()


def floor_app(robot_address: str) -> Flask:
    """The bare minimum the middleware is compared with: a route that does nothing, a route that makes one bare
    gRPC unary call to the skill server (the least any HTTP -> gRPC path can cost), a WebSocket echo."""
    app = Flask("floor")
    sock = Sock(app)
    channel = grpc.insecure_channel(robot_address)
    stub = robot_pb2_grpc.RobotStub(channel)

    @app.get("/ping")
    def ping():
        return "ok"

    @app.post("/relay")
    def relay():
        stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=5)
        return "ok"

    @sock.route("/echo")
    def echo(ws) -> None:
        while True:
            message = ws.receive()
            ws.send(message)

    return app


class WebSocketClient(simple_websocket.Client):
    """simple_websocket's client, minus a loss: its handshake reads the server's answer and takes only the first
    event, so frames that came in the same read (a refusal's error and close, or a channel's first message)
    waited in wsproto for more data that never came, and the socket ended as a bare 1005 close."""

    def _thread(self) -> None:
        self.connected = self._handle_events()  # what came with the handshake's answer
        super()._thread()

    def close(self, reason=None, message=None) -> None:
        """A close that races the server's: the reader thread may close the socket between the library's
        `connected` check and its send, which surfaced as OSError (EBADF) instead of ConnectionClosed. A socket the
        server already ended normally (1000, e.g. a goal channel after the goal's last status) is closed: closing
        it again is nothing to report, as a browser's close() would not."""
        try:
            super().close(reason=reason, message=message)
        except simple_websocket.ConnectionClosed:
            if self.close_reason != 1000:
                raise
        except OSError as error:
            if self.close_reason != 1000:
                raise simple_websocket.ConnectionClosed(self.close_reason, self.close_message) from error


class Browser:
    """A logged-in user: cookies, CSRF token, WebSockets with the session."""

    def __init__(self, base_url: str, username: str) -> None:
        self.base_url = base_url
        self.cookies = CookieJar()
        self.opener = build_opener(HTTPCookieProcessor(self.cookies), _NoRedirect())
        body = self.get("/login")[1]
        token = CSRF_FIELD.search(body).group(1)
        status, _ = self.send("POST", "/login", urlencode({"username": username, "password": PASSWORD,
                                                           "csrf_token": token}).encode())
        if status != 302:
            raise RuntimeError(f"{username} could not log in ({status})")
        self.csrf = CSRF_FIELD.search(self.get("/lab")[1]).group(1)

    def send(self, method: str, path: str, data: bytes | None = None,
             headers: dict[str, str] | None = None) -> tuple[int, str]:
        """(status, body) of one request."""
        request = Request(self.base_url + path, data=data, method=method, headers=headers or {})
        try:
            with self.opener.open(request, timeout=30) as response:
                return response.status, response.read().decode()
        except Exception as error:
            if hasattr(error, "code"):
                return error.code, error.read().decode()
            raise

    def get(self, path: str) -> tuple[int, str]:
        """A GET."""
        return self.send("GET", path)

    def post_json(self, path: str, body: object) -> tuple[int, str]:
        """A JSON POST with the CSRF header a page sends."""
        return self.send("POST", path, json.dumps(body).encode(),
                         {"Content-Type": "application/json", "X-CSRFToken": self.csrf})

    def websocket(self, path: str) -> simple_websocket.Client:
        """A WebSocket carrying the session cookie."""
        cookie = "; ".join(f"{c.name}={c.value}" for c in self.cookies)
        return WebSocketClient.connect(self.base_url.replace("http", "ws", 1) + path,
                                               headers={"Cookie": cookie})


class LabUnderTest:
    """Starts the skill server, the middleware and the floor app; creates the users."""

    def __init__(self, users: int) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="telelab-bench-"))
        self.robot = SkillServerProcess("lab-1", "lab")
        self.robot.start()
        wait_until_serving(self.robot.address)
        database_url = f"sqlite:///{self.folder / 'bench.sqlite3'}"
        upgrade_to_head(database_url)
        self.app = create_app({"DATABASE_URL": database_url, "SECRET_KEY": secrets.token_hex(16),
                               "ROBOTS": parse_robots(f"lab-1={self.robot.address}")})
        self.app.instance_path = str(self.folder / "instance")
        # Every user gets the same scrypt hash of PASSWORD, computed once (as web_tier.py's students): a hash costs
        # about 0.1 s, and each login still checks one on the server, as it does in use.
        one_hash = services.hash_password(PASSWORD)
        with (session_factory(self.app)() as session,
              mock.patch.object(services, "generate_password_hash", lambda *_args, **_kwargs: one_hash)):
            for index in range(users):
                create_user(session, f"bench{index}", "student", PASSWORD)
            session.commit()
        self.usernames = [f"bench{i}" for i in range(users)]
        self.middleware = Served(self.app)
        self.floor = Served(floor_app(self.robot.address))
        self.floor_client = build_opener()

    def browser(self, index: int = 0) -> Browser:
        """User number index, logged in."""
        return Browser(self.middleware.url, self.usernames[index])

    def floor_request(self, path: str = "/ping", body: bytes | None = None) -> float:
        """One request to a floor route, in seconds, on a new connection through the same client (urllib) as
        the users' requests, so the client's own cost is in the floor too."""
        request = Request(self.floor.url + path, data=body, method="GET" if body is None else "POST",
                          headers={} if body is None else {"Content-Type": "application/json"})
        started = time.perf_counter()
        with self.floor_client.open(request, timeout=10) as response:
            response.read()
        return time.perf_counter() - started

    def stop(self) -> None:
        """Stops everything."""
        from middleware.access.coordinator import access_coordinator
        from middleware.robots.registry import robot_registry

        self.middleware.stop()
        self.floor.stop()
        access_coordinator(self.app).stop_ticker()
        robot_registry(self.app).close()
        self.robot.stop()
