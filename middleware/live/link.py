"""One WebSocket per page that carries all its channels: /ws/link.

The page subscribes to a channel by its path (`{"type": "subscribe", "sub": 7, "path": "/ws/robots/lab-1/camera"}`)
and the channel is opened exactly as if that path had been connected on its own (the same checks, in a request
made from the link's own headers: its login cookie, Origin and Host), then served on the link:

- server to page: a text message `"7 <text>"`, a binary message of 4 bytes (7, big-endian) + the channel's bytes;
  on sub 0, `{"type": "ready", "max_channels": 24}` once, then `{"type": "subscribed", "sub": 7}` and
  `{"type": "closed", "sub": 7, "code": 4404, "reason": "..."}`;
- page to server: `"7 <text>"` to channel 7, `{"type": "unsubscribe", "sub": 7}`.

A channel's close code means what it means on its own socket (transport.js: final or try again).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from flask import Flask
from simple_websocket import ConnectionClosed
from werkzeug.exceptions import HTTPException

from middleware.errors import Refused
from middleware.live.codes import (
    CLOSE_FORBIDDEN,
    CLOSE_NOT_FOUND,
    CLOSE_NOT_LOGGED_IN,
    CLOSE_SERVER_FAILED,
    CLOSE_TRY_AGAIN_LATER,
)
from middleware.live.loop import Continuation
from middleware.live.wire import Inbox, LiveSocket
from middleware.validation import InvalidInput, decimal_int, parse_message

log = logging.getLogger(__name__)
_REFUSAL_CLOSE_CODES = {401: CLOSE_NOT_LOGGED_IN, 403: CLOSE_FORBIDDEN, 429: CLOSE_TRY_AGAIN_LATER,
                        503: CLOSE_TRY_AGAIN_LATER}
_CHANNEL_NUMBER = re.compile(r"[0-9]+")  # ASCII digits only: '²'.isdigit() is true
MAX_SUBSCRIPTIONS = 24  # a console subscribes about ten
MAX_SUB_ID = 2**31 - 1
MAX_PATH_LENGTH = 256
LINK_PATH = "/ws/link"


@dataclass(frozen=True)
class Declared:
    """A channel as `Channels.route` declared it."""

    opener: Callable[..., Continuation | None]
    messages_per_s: int


class RecordingSocket:
    """What a channel's opener is given on a link: what it sends and its refusal are recorded, then forwarded."""

    def __init__(self) -> None:
        self.sent: list[str | bytes] = []
        self.closed: tuple[int, str] | None = None
        self.connected = True

    def send(self, data: str | bytes) -> None:
        if not self.connected:
            raise ConnectionClosed(1000, "")
        self.sent.append(data)

    def close(self, reason: int | None = None, message: str | None = None) -> None:
        if not self.connected:
            raise ConnectionClosed(1000, "")
        self.connected = False
        self.closed = (reason or 1000, message or "")


class SubSocket(Inbox):
    """One channel carried on a link: what a continuation sees of it is what it sees of a socket of its own."""

    def __init__(self, link: LiveSocket, sub: int, inbound: Any) -> None:
        super().__init__(inbound)
        self._link, self.sub = link, sub
        link.carried.add(self)
        self.connected = True
        self.close_reason, self.close_message = 1000, ""
        self._prefix = f"{sub} "
        self._binary_prefix = sub.to_bytes(4, "big")

    def silent_s(self) -> float:
        return self._link.silent_s()

    def _framed(self, data: str | bytes) -> str | bytes:
        if not self.connected:
            raise ConnectionClosed(self.close_reason, self.close_message)
        return self._prefix + data if isinstance(data, str) else self._binary_prefix + data

    def write(self, data: str | bytes) -> None:
        self._raise_if_overflowed()
        self._link.write(self._framed(data))

    async def send(self, data: str | bytes) -> None:
        self._raise_if_overflowed()
        await self._link.send(self._framed(data))

    def send_latest(self, data: str | bytes) -> bool:
        return self._link.send_latest(self._framed(data))

    def begin_close(self, reason: int, message: str) -> None:
        self._link.carried.discard(self)
        if self.connected:
            self.connected = False
            self.close_reason, self.close_message = reason, message
            with contextlib.suppress(ConnectionClosed):
                self._link.write(control({"type": "closed", "sub": self.sub, "code": reason,
                                          "reason": message[:120]}))
        self.nudge()

    async def close(self, reason: int | None = None, message: str | None = None) -> None:
        """Ends the channel; the page hears its code on sub 0. The link stays open."""
        self.begin_close(reason or 1000, message or "")

    def admit(self, message: str | bytes) -> None:
        if self.connected and self.inbound.overflow is None:
            self._admit(message)


def control(message: dict[str, object]) -> str:
    return "0 " + json.dumps(message, separators=(",", ":"))


class Link:
    """The server's side of one page's link: its subscriptions and the channels serving them."""

    def __init__(self, live: LiveSocket, app: Flask, open_sub: Callable[[str], Any],
                 make_inbound: Callable[[int], Any], on_overflow: Callable[[str], None]) -> None:
        self.live, self.app = live, app
        self._open_sub = open_sub  # path -> awaitable of (Declared-rule, opened continuation, RecordingSocket)
        self._make_inbound = make_inbound
        self._on_overflow = on_overflow
        self._subs: dict[int, tuple[SubSocket, asyncio.Task[None]]] = {}

    async def serve(self) -> None:
        self.live.write(control({"type": "ready", "max_channels": MAX_SUBSCRIPTIONS}))
        try:
            while self.live.connected:
                raw = await self.live.receive(timeout=None)
                if raw is not None:
                    await self._take(raw)
        finally:
            for sub, _task in list(self._subs.values()):
                await sub.close(1001, "The page left.")
            tasks = [task for _sub, task in self._subs.values()]
            if tasks:
                await asyncio.wait(tasks, timeout=5.0)

    async def _take(self, raw: str | bytes) -> None:
        if isinstance(raw, bytes):
            return self._error("A link takes text messages only.", "message")
        head, _, payload = raw.partition(" ")
        if _CHANNEL_NUMBER.fullmatch(head):
            sub = decimal_int(head, 1, MAX_SUB_ID)
            if sub is None:
                return self._error(f"A channel's number is a whole number from 1 to {MAX_SUB_ID}.", "sub")
            entry = self._subs.get(sub)
            if entry is not None:  # a message to a channel closed meanwhile is dropped
                entry[0].admit(payload)
            return None
        try:
            message = parse_message(raw, ("subscribe", "unsubscribe"), len(raw))
        except InvalidInput as refused:
            return self._error(refused.message, refused.field or "message")
        sub = message.get("sub")
        if not isinstance(sub, int) or isinstance(sub, bool) or not 0 < sub <= MAX_SUB_ID:
            return self._error(f"sub must be a whole number from 1 to {MAX_SUB_ID}.", "sub")
        if message["type"] == "unsubscribe":
            entry = self._subs.get(sub)
            if entry is not None:
                await entry[0].close(1000, "Unsubscribed.")
            return None
        path = message.get("path")
        if not isinstance(path, str) or not path.startswith("/ws/") or len(path) > MAX_PATH_LENGTH:
            return self._error(f"path must be a channel's path (/ws/..., at most {MAX_PATH_LENGTH} characters).",
                               "path")
        if sub in self._subs:
            return self._error(f"Channel {sub} is open already; unsubscribe it first.", "sub")
        if len(self._subs) >= MAX_SUBSCRIPTIONS:
            return self._error(f"A link carries at most {MAX_SUBSCRIPTIONS} channels.", "sub")
        await self._subscribe(sub, path)
        return None

    async def _subscribe(self, sub: int, path: str) -> None:
        placeholder = SubSocket(self.live, sub, self._make_inbound(1))
        self._subs[sub] = (placeholder, asyncio.ensure_future(asyncio.sleep(0)))  # reserved while it opens
        try:
            rule, declared, continuation, opening = await self._open_sub(path)
        except HTTPException:
            self._subs.pop(sub, None)
            return self._closed(sub, CLOSE_NOT_FOUND, "There is no channel at that path.")
        except CoolingDown as cooling:
            self._subs.pop(sub, None)
            return self._closed(sub, CLOSE_TRY_AGAIN_LATER, str(cooling))
        except Refused as refused:  # the path's text (a NUL), or an opener's refusal: this channel's, not the link's
            self._subs.pop(sub, None)
            return self._closed(sub, _REFUSAL_CLOSE_CODES.get(refused.status, CLOSE_NOT_FOUND), refused.message)
        except Exception:
            self._subs.pop(sub, None)
            log.exception("opening a channel on a link failed")
            return self._closed(sub, CLOSE_SERVER_FAILED, "The server failed on this channel; try again.")
        channel = SubSocket(self.live, sub, self._make_inbound(declared.messages_per_s))
        channel.on_overflow = lambda: self._on_overflow(rule)
        self.live.write(control({"type": "subscribed", "sub": sub}))
        for data in opening.sent:
            channel.write(data)
        if continuation is None or opening.closed is not None:
            code, reason = opening.closed or (1000, "")
            self._subs.pop(sub, None)
            await channel.close(code, reason)
            return None
        self._subs[sub] = (channel, asyncio.ensure_future(self._run(channel, continuation)))
        return None

    async def _run(self, channel: SubSocket, continuation: Continuation) -> None:
        try:
            await continuation(channel)  # type: ignore[arg-type]
        except ConnectionClosed:
            pass
        except Exception:  # as on a socket of its own: this channel ends with 1011, the link and the others stay
            log.exception("a channel on a link failed")
            channel.begin_close(CLOSE_SERVER_FAILED, "The server failed on this channel; reload the page.")
        finally:
            await channel.close(channel.close_reason if not channel.connected else 1000, channel.close_message)
            self._subs.pop(channel.sub, None)

    def _closed(self, sub: int, code: int, reason: str) -> None:
        self.live.write(control({"type": "subscribed", "sub": sub}))
        self.live.write(control({"type": "closed", "sub": sub, "code": code, "reason": reason[:120]}))

    def _error(self, message: str, field: str) -> None:
        self.live.write(control({"type": "error", "code": "invalid_field", "message": message, "field": field}))


class CoolingDown(Exception):
    """The user was closed for flooding this channel lately."""
