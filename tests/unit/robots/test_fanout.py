"""Fan-out: one upstream stream, packed once per message, latest wins for a slow viewer."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import AsyncIterator

from middleware.robots.fanout import FanoutHub


class Upstream:
    """A stand-in for the robot's grpc.aio stream (the real one is exercised in the integration tests)."""

    def __init__(self) -> None:
        self.opened = 0
        self.cancelled = threading.Event()
        self.packs = 0

    def open(self) -> AsyncIterator[object]:
        self.opened += 1
        return self._messages()

    async def _messages(self) -> AsyncIterator[object]:
        n = 0
        while not self.cancelled.is_set():
            n += 1
            yield n
            await asyncio.sleep(0.005)

    def pack(self, item: object) -> object:
        self.packs += 1
        return ("packed", item)

    def cancel(self, _stream: object) -> None:
        self.cancelled.set()


def test_every_viewer_shares_one_upstream_and_one_pack_per_message() -> None:
    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    viewers = [hub.subscribe() for _ in range(20)]
    received = [[v.next_message(2.0) for _ in range(5)] for v in viewers]
    assert upstream.opened == 1
    assert all(all(m is not None for m in messages) for messages in received)
    assert upstream.packs == hub.messages_packed
    for viewer in viewers:
        viewer.close()
    assert upstream.cancelled.wait(2.0), "the last viewer leaving cancels the upstream stream"
    hub.close()


def test_a_slow_viewer_gets_the_newest_message_and_no_backlog() -> None:
    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    viewer = hub.subscribe()
    first = viewer.next_message(2.0)
    time.sleep(0.2)  # meanwhile dozens of messages arrive
    newest = viewer.next_message(2.0)
    assert first is not None and newest is not None
    assert newest[1] - first[1] > 5, "the slow viewer skipped to the newest message"
    following = viewer.next_message(2.0)
    assert following is not None and following[1] > newest[1]
    viewer.close()
    hub.close()


def test_a_failing_upstream_reports_offline_and_reconnects() -> None:
    attempts = []

    async def flaky() -> AsyncIterator[object]:
        attempts.append(time.monotonic())
        if len(attempts) < 3:
            raise ConnectionError("robot down")
        yield "hello"
        while True:
            await asyncio.sleep(0.01)
            yield "again"

    hub = FanoutHub("t", flaky, lambda item: item, lambda _s: None, backoff_s=(0.01, 0.05))
    viewer = hub.subscribe()
    assert viewer.next_message(3.0) in {"hello", "again"}
    assert len(attempts) == 3
    statuses = viewer.status_change()
    assert statuses is not None and statuses.online
    viewer.close()
    hub.close()


class GoneViewer:
    """A viewer socket whose peer has vanished: writing to it fails as a closed tab's does."""

    connected = True
    sends = 0

    def send_latest(self, _message: object) -> bool:
        from simple_websocket import ConnectionClosed

        self.sends += 1
        raise ConnectionClosed(1006, "")

    write = send_latest

    async def send(self, message: object) -> None:
        self.send_latest(message)

    async def receive(self, timeout: float = 0) -> None:
        return None


def _relay_on_the_channel_loop(viewer: object, hub: FanoutHub) -> object:
    """relay_stream served as the channel loop serves it (a future of its end)."""
    import asyncio

    from middleware.live.loop import channel_loop
    from middleware.realtime import relay_stream

    return asyncio.run_coroutine_threadsafe(relay_stream(viewer, hub), channel_loop().loop)  # type: ignore[arg-type]


def test_a_viewer_gone_mid_send_ends_its_stream_and_releases_the_upstream() -> None:
    from simple_websocket import ConnectionClosed

    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    viewer = GoneViewer()
    relay = _relay_on_the_channel_loop(viewer, hub)
    try:
        relay.result(3.0)  # type: ignore[attr-defined]
        raise AssertionError("a send to a gone viewer must end the relay")
    except ConnectionClosed:
        pass  # the channel loop takes this as the client having gone, not as a server error
    assert viewer.sends == 1
    assert upstream.cancelled.wait(2.0), "its subscription was closed"
    hub.close()


class StayingViewer:
    """A viewer whose tab stays open: it accepts every frame and never closes."""

    connected = True

    def __init__(self) -> None:
        self.sends = 0
        self.closed_with: int | None = None

    def send_latest(self, _data: object) -> bool:
        self.sends += 1
        return True

    def write(self, data: object) -> None:
        self.send_latest(data)

    async def send(self, data: object) -> None:
        self.send_latest(data)

    async def receive(self, timeout: float = 0) -> None:
        return None

    async def close(self, reason: int | None = None, _message: str | None = None) -> None:
        self.closed_with, self.connected = reason, False


def test_closing_the_hub_ends_an_open_viewer_s_stream_instead_of_spinning() -> None:
    from middleware.realtime import CLOSE_GOING_AWAY

    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    viewer = StayingViewer()
    relay = _relay_on_the_channel_loop(viewer, hub)
    deadline = time.monotonic() + 2.0
    while viewer.sends == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert viewer.sends > 0
    hub.close()  # the application shuts down while the tab is still open
    relay.result(2.0)  # type: ignore[attr-defined]  # raises TimeoutError if it kept looping on the closed hub
    assert viewer.closed_with == CLOSE_GOING_AWAY


def test_hubs_pump_on_the_channel_loop_so_threads_do_not_grow_with_streams() -> None:
    """The old hubs ran a pump thread per watched stream (3 per robot: camera, telemetry, localization)."""
    warm = FanoutHub("warm", Upstream().open, lambda item: item, lambda _s: None)
    warm.subscribe().next_message(2.0)  # the channel loop and its thread exist from here on
    before = threading.active_count()
    upstreams = [Upstream() for _ in range(150)]
    hubs = [FanoutHub(f"r{i}", u.open, u.pack, u.cancel) for i, u in enumerate(upstreams)]
    viewers = [hub.subscribe() for hub in hubs]
    assert all(viewer.next_message(5.0) is not None for viewer in viewers)
    assert threading.active_count() - before <= 2, [t.name for t in threading.enumerate()]
    for viewer in viewers:
        viewer.close()
    assert all(u.cancelled.wait(3.0) for u in upstreams)
    for hub in [*hubs, warm]:
        hub.close()


def test_a_viewer_arriving_as_the_last_one_leaves_gets_a_pump_again() -> None:
    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    for _ in range(20):
        viewer = hub.subscribe()
        assert viewer.next_message(3.0) is not None
        viewer.close()  # the pump's cancellation is on its way while the next viewer subscribes
        upstream.cancelled.clear()
    last = hub.subscribe()
    assert last.next_message(3.0) is not None
    last.close()
    deadline = time.monotonic() + 3.0
    while hub.pumping and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not hub.pumping, "the pump retires once nobody watches"
    hub.close()


def test_a_message_is_packed_only_when_a_viewer_asks_for_it_packed() -> None:
    upstream = Upstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    sampler = hub.subscribe()  # the class wall: a few fields of the message as it came, now and then
    items = [sampler.next_item(2.0) for _ in range(5)]
    assert all(isinstance(item, int) for item in items)
    time.sleep(0.1)  # dozens more arrive
    assert upstream.packs == 0, "messages nobody asked for packed were packed"
    reader = hub.subscribe()  # a console: every message it reads, packed
    packed = [reader.next_message(2.0) for _ in range(3)]
    assert all(message is not None and message[0] == "packed" for message in packed)
    assert upstream.packs == hub.messages_packed == 3
    for viewer in (sampler, reader):
        viewer.close()
    hub.close()


class NumberedUpstream(Upstream):
    """Each message says which opening of the stream it came from; the first comes 0.2 s after the opening (a robot
    answers a new call after a round trip)."""

    async def _messages(self) -> AsyncIterator[object]:
        opening = self.opened
        await asyncio.sleep(0.2)
        while not self.cancelled.is_set():
            yield opening
            await asyncio.sleep(0.005)


def test_a_viewer_after_the_pump_stopped_waits_for_a_new_message_not_the_one_left_from_before() -> None:
    upstream = NumberedUpstream()
    hub = FanoutHub("t", upstream.open, upstream.pack, upstream.cancel)
    first = hub.subscribe()
    assert first.next_message(2.0) == ("packed", 1)
    first.close()
    assert upstream.cancelled.wait(2.0)
    deadline = time.monotonic() + 2
    while hub.pumping and time.monotonic() < deadline:
        time.sleep(0.01)
    upstream.cancelled.clear()
    later = hub.subscribe()
    try:
        assert later.next_message(2.0) == ("packed", 2)  # from the stream opened for it, not what was left before
    finally:
        later.close()
        hub.close()
