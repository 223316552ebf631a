"""A static file server for client_ui/static and a Chromium tab on it, to run pure ES modules' tests."""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterator
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

STATIC_DIR = Path(__file__).resolve().parents[3] / "client_ui" / "static"


class _QuietHandler(SimpleHTTPRequestHandler):
    extensions_map = {**SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"}

    def log_message(self, *_args) -> None:
        pass


@pytest.fixture(scope="module")
def static_url() -> Iterator[str]:
    """client_ui/static served on a free loopback port."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(STATIC_DIR)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_port}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def module_page(chromium, static_url: str):
    """A blank tab on the static server; evaluate(js) may `await import('/lib/...')`."""
    context = chromium.new_context()
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    tab.goto(f"{static_url}/lib/")
    yield tab
    context.close()
    assert not errors, errors
