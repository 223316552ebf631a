"""A WebSocket client that sends as fast as it is allowed to, for the back-pressure tests; run in a process of its
own so that its work does not compete with the test's measurements for one interpreter.

    python -m tests.integration.middleware.flood_client WS_URL COOKIE KIND SECONDS RATE_PER_S

It reconnects at once when the server closes it, 0.1 s after a refused handshake, and prints
"flooding" when it starts, then one JSON line: messages sent, connections opened, and the close codes and
reasons (or refused handshakes) the server answered.
"""

from __future__ import annotations

import json
import sys
import time
from collections import Counter

import simple_websocket
from wsproto.events import TextMessage
from wsproto.utilities import LocalProtocolError

from benchmarks.lab_under_test import WebSocketClient

BATCH = 50
# Far quicker than a browser's backoff; without any pause this would be a flood of handshakes, which costs the
# web process about 7 ms each however it answers: a matter for the HTTP edge, not for the sockets' limits.
RETRY_AFTER_REFUSAL_S = 0.1


def messages(kind: str, first_sequence: int) -> list[str]:
    """A batch of the channel's own kind of message (drive commands with rising sequence numbers)."""
    if kind == "chat":
        return [json.dumps({"type": "say", "body": "flood " * 80})] * BATCH
    if kind == "queue":
        return [json.dumps({"type": "join"})] * BATCH
    return [json.dumps({"type": "drive", "sequence": first_sequence + i, "linear_mps": 0.0, "angular_radps": 0.1})
            for i in range(BATCH)]


def flood(url: str, cookie: str, kind: str, seconds: float, rate_per_s: float) -> dict[str, object]:
    """Floods url for seconds at up to rate_per_s messages a second; the tally."""
    sent = connections = 0
    closes: Counter[str] = Counter()
    ws = WebSocketClient.connect(url, headers={"Cookie": cookie})
    print("flooding", flush=True)  # the test measures from here
    ends_at = time.monotonic() + seconds
    while time.monotonic() < ends_at:
        if connections:
            try:
                ws = WebSocketClient.connect(url, headers={"Cookie": cookie})
            except simple_websocket.ConnectionError as refused:
                closes[f"handshake {refused.status_code}"] += 1
                time.sleep(RETRY_AFTER_REFUSAL_S)
                continue
        connections += 1
        sequence = 1
        next_batch_at = time.monotonic()
        try:
            while ws.connected and time.monotonic() < ends_at:
                frames = b"".join(ws.ws.send(TextMessage(data=m)) for m in messages(kind, sequence))
                ws.sock.sendall(frames)
                sent += BATCH
                sequence += BATCH
                next_batch_at += BATCH / rate_per_s
                time.sleep(max(0.0, next_batch_at - time.monotonic()))
        except (OSError, LocalProtocolError):
            pass  # the server closed or cut us off
        ws.thread.join(2)
        closes[f"{ws.close_reason} {ws.close_message or ''}".strip()] += 1
        if ws.connected:
            ws.close()
    return {"sent": sent, "seconds": seconds, "connections": connections, "closes": dict(closes)}


if __name__ == "__main__":
    url, cookie, kind, seconds, rate = sys.argv[1:6]
    print(json.dumps(flood(url, cookie, kind, float(seconds), float(rate))), flush=True)
