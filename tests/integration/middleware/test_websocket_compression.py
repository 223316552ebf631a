"""No channel negotiates permessage-deflate: a small compressed frame would inflate to megabytes in the web
process before the message size limit could see it."""

from __future__ import annotations

import base64
import os
import socket
from urllib.parse import urlsplit

from tests.conftest import LabClient
from tests.integration.middleware.test_websocket_origin import websocket_paths


def handshake_answer(client: LabClient, path: str, extensions: str) -> str:
    """The server's answer (status line and headers) to a WebSocket handshake offering extensions."""
    address = urlsplit(client.base_url)
    key = base64.b64encode(os.urandom(16)).decode()
    request = (f"GET {path} HTTP/1.1\r\nHost: {address.netloc}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Extensions: {extensions}\r\n"
               f"Cookie: {client.cookie_header()}\r\n\r\n")
    with socket.create_connection((address.hostname, address.port), timeout=5) as conn:
        conn.sendall(request.encode())
        answer = b""
        while b"\r\n\r\n" not in answer:
            chunk = conn.recv(4096)
            if not chunk:
                break
            answer += chunk
    return answer.split(b"\r\n\r\n", 1)[0].decode("latin-1")


def test_no_channel_accepts_compression(student_client: LabClient, app) -> None:
    for path in websocket_paths(app):
        answer = handshake_answer(student_client, path, "permessage-deflate; client_max_window_bits")
        assert answer.startswith("HTTP/1.1 101"), (path, answer)
        assert "sec-websocket-extensions" not in answer.lower(), (path, answer)
