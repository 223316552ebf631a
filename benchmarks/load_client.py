"""Logged-in users as a load process holds them: HTTP/1.1 with keep-alive and WebSockets framed by hand, on asyncio.

No client library sits between the socket and the count: a poll is one write and two reads on a connection kept
open, and a WebSocket frame is parsed from its two to ten header bytes (the server's frames are not masked). So one
process holds thousands of users on a small share of one core, and what a benchmark measures is the server, not its
load. Pings are answered (the server closes a socket that does not answer), and a frame a client sends is masked as
RFC 6455 requires.
"""

from __future__ import annotations

import asyncio
import base64
import multiprocessing
import os
import queue
import time
from collections.abc import Callable
from typing import Any

OP_CONTINUATION, OP_TEXT, OP_BINARY, OP_CLOSE, OP_PING, OP_PONG = 0x0, 0x1, 0x2, 0x8, 0x9, 0xA
HEAD_LIMIT = 1 << 16


class Refused(Exception):
    """The server answered a WebSocket handshake with something other than 101."""


def _masked(payload: bytes, key: bytes) -> bytes:
    size = len(payload)
    if not size:
        return payload
    stream = (key * (size // 4 + 1))[:size]
    return (int.from_bytes(payload, "big") ^ int.from_bytes(stream, "big")).to_bytes(size, "big")


def client_frame(opcode: int, payload: bytes) -> bytes:
    """One final frame from a client (masked)."""
    key = os.urandom(4)
    size = len(payload)
    if size < 126:
        head = bytes((0x80 | opcode, 0x80 | size))
    elif size < 1 << 16:
        head = bytes((0x80 | opcode, 0x80 | 126)) + size.to_bytes(2, "big")
    else:
        head = bytes((0x80 | opcode, 0x80 | 127)) + size.to_bytes(8, "big")
    return head + key + _masked(payload, key)


class HttpUser:
    """One user's keep-alive connection: GETs with the user's cookie, reconnecting when the server closes it."""

    def __init__(self, port: int, cookie: str) -> None:
        self.port = port
        self._head = f"Host: 127.0.0.1:{port}\r\nCookie: {cookie}\r\nAccept: application/json\r\n\r\n"
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None

    async def get(self, path: str) -> int:
        """The status of one GET (its body is read and dropped); one retry on a connection the server had closed."""
        for attempt in (1, 2):
            if self._writer is None:
                self._reader, self._writer = await asyncio.open_connection("127.0.0.1", self.port, limit=HEAD_LIMIT)
            assert self._reader is not None
            try:
                self._writer.write(f"GET {path} HTTP/1.1\r\n{self._head}".encode())
                head = await self._reader.readuntil(b"\r\n\r\n")
                status, length, chunked, closing = _parse_head(head)
                if chunked:
                    await _skip_chunks(self._reader)
                else:
                    await self._reader.readexactly(length)
            except (ConnectionError, asyncio.IncompleteReadError, asyncio.LimitOverrunError):
                self.close()
                if attempt == 2:
                    raise
                continue
            if closing:
                self.close()
            return status
        raise AssertionError("unreachable")

    def close(self) -> None:
        """Drops the connection."""
        if self._writer is not None:
            self._writer.close()
        self._reader = self._writer = None


def _parse_head(head: bytes) -> tuple[int, int, bool, bool]:
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split(" ", 2)[1])
    length, chunked, closing = 0, False, False
    for line in lines[1:]:
        name, _, value = line.partition(":")
        name, value = name.strip().lower(), value.strip().lower()
        if name == "content-length":
            length = int(value)
        elif name == "transfer-encoding":
            chunked = "chunked" in value
        elif name == "connection":
            closing = value == "close"
    return status, length, chunked, closing


async def _skip_chunks(reader: asyncio.StreamReader) -> None:
    while True:
        size = int((await reader.readuntil(b"\r\n")).split(b";", 1)[0], 16)
        await reader.readexactly(size + 2)
        if size == 0:
            return


class WebSocketUser:
    """One WebSocket of a logged-in user: opened with the session cookie and the page's Origin."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._reader, self._writer = reader, writer
        self.close_code: int | None = None

    @classmethod
    async def open(cls, port: int, path: str, cookie: str) -> WebSocketUser:
        """Connects and completes the handshake, or raises Refused."""
        reader, writer = await asyncio.open_connection("127.0.0.1", port, limit=HEAD_LIMIT)
        host = f"127.0.0.1:{port}"
        key = base64.b64encode(os.urandom(16)).decode()
        writer.write((f"GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                      f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: http://{host}\r\n"
                      f"Cookie: {cookie}\r\n\r\n").encode())
        head = await reader.readuntil(b"\r\n\r\n")
        status = int(head.split(b" ", 2)[1])
        if status != 101:
            writer.close()
            raise Refused(f"{path} answered {status}")
        return cls(reader, writer)

    def send_text(self, text: str) -> None:
        """Sends one text message."""
        self._writer.write(client_frame(OP_TEXT, text.encode()))

    async def read_messages(self, on_message: Callable[[int, bytes], None]) -> int | None:
        """Calls on_message(opcode, payload) for every message until the socket closes; answers pings. Returns the
        server's close code (None when the connection just ended)."""
        buffer = b""
        fragments: list[bytes] = []
        fragment_opcode = OP_TEXT
        while True:
            chunk = await self._reader.read(HEAD_LIMIT)
            if not chunk:
                return self.close_code
            buffer += chunk
            offset = 0
            while len(buffer) - offset >= 2:
                first, second = buffer[offset], buffer[offset + 1]
                size, start = second & 0x7F, offset + 2
                if size == 126:
                    if len(buffer) - start < 2:
                        break
                    size, start = int.from_bytes(buffer[start:start + 2], "big"), start + 2
                elif size == 127:
                    if len(buffer) - start < 8:
                        break
                    size, start = int.from_bytes(buffer[start:start + 8], "big"), start + 8
                if len(buffer) - start < size:
                    break
                payload, offset, opcode = buffer[start:start + size], start + size, first & 0x0F
                if opcode == OP_PING:
                    self._writer.write(client_frame(OP_PONG, payload))
                elif opcode == OP_CLOSE:
                    self.close_code = int.from_bytes(payload[:2], "big") if len(payload) >= 2 else 1005
                    self._writer.write(client_frame(OP_CLOSE, payload[:2]))
                    return self.close_code
                elif opcode in (OP_TEXT, OP_BINARY, OP_CONTINUATION):
                    if opcode != OP_CONTINUATION:
                        fragment_opcode = opcode
                    if first & 0x80:  # FIN
                        on_message(fragment_opcode, b"".join(fragments) + payload if fragments else payload)
                        fragments = []
                    else:
                        fragments.append(payload)
            buffer = buffer[offset:]

    def close(self) -> None:
        """Closes with 1000 and drops the connection."""
        if not self._writer.is_closing():
            self._writer.write(client_frame(OP_CLOSE, (1000).to_bytes(2, "big")))
            self._writer.close()


class LoadProcess:
    """A load generator in a process of its own (spawned: nothing of the benchmark's state comes along), run by
    target(commands, reports): it answers each (command, argument) with one (command, report); "stop" ends it."""

    def __init__(self, target: Callable[..., None]) -> None:
        context = multiprocessing.get_context("spawn")
        self.commands, self.reports = context.Queue(), context.Queue()
        self.process = context.Process(target=target, args=(self.commands, self.reports), daemon=True)
        self.process.start()

    def ask(self, command: str, argument: object, timeout_s: float) -> Any:
        """Sends a command and returns its report."""
        self.commands.put((command, argument))
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if not self.process.is_alive():
                raise RuntimeError(f"the load process ended (exit code {self.process.exitcode})")
            try:
                return self.reports.get(timeout=1.0)[1]
            except queue.Empty:
                continue
        raise RuntimeError(f"the load process did not answer {command!r} in {timeout_s:.0f} s")

    def stop(self) -> None:
        """Every user leaves and the process ends."""
        try:
            self.ask("stop", None, 60)
        finally:
            self.process.join(30)
            if self.process.is_alive():
                self.process.kill()
