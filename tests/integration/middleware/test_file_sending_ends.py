"""A browser that resets its connection as a file is sent leaves no open file behind in the server."""

from __future__ import annotations

import gc
import socket
import struct
import sys
import threading
import time
from pathlib import Path

from flask import Flask

from middleware.serve import make_threaded_server


def _fetch_then_reset(port: int, path: str) -> None:
    """Asks for path with a stray byte after the request, reads the answer, and resets the connection (SO_LINGER 0),
    as a page left mid-load does. The server is then draining that byte's connection, and the reset fails its read."""
    with socket.create_connection(("127.0.0.1", port)) as client:
        client.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\nx".encode())
        received = b""
        while b"\r\n\r\n" not in received or not received.endswith(b"//"):
            received += client.recv(65536)
        client.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))


def test_a_file_sent_to_a_browser_that_resets_the_connection_is_closed_not_left_to_the_collector(tmp_path: Path):
    static = tmp_path / "static"
    static.mkdir()
    (static / "module.js").write_bytes(b"//" * 1000)
    app = Flask(__name__, static_folder=str(static))
    server = make_threaded_server(app, "127.0.0.1", 0)
    threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()
    serving = threading.active_count()
    left_open: list[str] = []
    hook, sys.unraisablehook = sys.unraisablehook, lambda seen: left_open.append(repr(seen.object))
    try:
        for _ in range(3):
            _fetch_then_reset(server.server_port, "/static/module.js")
        # The request threads end on their own time; then one collection (in a suite's process, with its heap, a
        # collection takes seconds: ten of them took 37 s).
        deadline = time.monotonic() + 10
        while threading.active_count() > serving and time.monotonic() < deadline:
            time.sleep(0.05)
        gc.collect()
    finally:
        sys.unraisablehook = hook
        server.shutdown()
        server.server_close()
    assert left_open == []
