"""The bounded inbound queue every WebSocket channel reads from: a rate with a burst, a cap on what waits, and
everything waiting dropped once the client is over either."""

from __future__ import annotations

import time

from middleware.realtime import InboundQueue


def test_a_burst_of_one_seconds_worth_is_admitted_and_the_next_message_overflows() -> None:
    queue = InboundQueue(per_s=10)
    for n in range(10):
        queue.append(f"m{n}")
    assert len(queue) == 10 and queue.overflow is None
    assert queue.pop() == "m0"
    queue.append("one too many")
    assert queue.overflow == "Too many messages: this channel takes at most 10 a second."
    assert len(queue) == 0 and queue.pop() is None, "what waited is dropped, not handled"
    queue.append("later")
    assert len(queue) == 0, "an overflowed queue admits nothing more"


def test_a_client_within_the_rate_is_never_refused() -> None:
    queue = InboundQueue(per_s=100)
    for _ in range(50):
        queue.append("drive")
        assert queue.pop() == "drive"
        time.sleep(0.011)  # a little slower than 100 a second
    assert queue.overflow is None


def test_messages_piling_up_unhandled_overflow_even_within_the_rate() -> None:
    queue = InboundQueue(per_s=100)
    for _ in range(100):
        queue.append("x")
    time.sleep(0.05)  # the allowance refills, but nobody took the hundred waiting
    queue.append("x")
    assert queue.overflow == "Messages came faster than this channel can handle them."
    assert len(queue) == 0
