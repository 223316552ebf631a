"""A hub's news reaches the channel loop's viewers: at once when the hub's pump runs on that loop (as every robot
stream's does), through the loop when it comes from another thread (a hub closed by the application)."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable

from middleware.live.loop import StreamWatch


class Hub:
    """The listening side of a FanoutHub: what StreamWatch uses of it."""

    def __init__(self) -> None:
        self.listeners: list[Callable[[], None]] = []

    def listen(self, news: Callable[[], None]) -> None:
        self.listeners.append(news)

    def tell(self) -> None:
        for news in self.listeners:
            news()


def _loop_in_a_thread() -> tuple[asyncio.AbstractEventLoop, threading.Thread]:
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    return loop, thread


def _stop(loop: asyncio.AbstractEventLoop, thread: threading.Thread) -> None:
    loop.call_soon_threadsafe(loop.stop)
    thread.join(5)
    loop.close()


def test_news_from_a_pump_on_the_loop_wakes_its_viewers_before_the_pump_goes_on() -> None:
    loop, thread = _loop_in_a_thread()
    try:
        hub = Hub()

        async def pump_tells() -> tuple[bool, bool]:
            watch = StreamWatch(asyncio.get_running_loop(), hub)
            viewers = [watch.join(), watch.join()]
            hub.tell()  # as FanoutHub._pump_while_wanted does after each message, with no await in between
            woken = all(viewer.is_set() for viewer in viewers)
            for viewer in viewers:
                viewer.clear()
            watch.leave(viewers[1])
            hub.tell()
            return woken, viewers[0].is_set() and not viewers[1].is_set()

        woken_at_once, only_those_watching = asyncio.run_coroutine_threadsafe(pump_tells(), loop).result(5)
        assert woken_at_once, "no hop through the loop's self-pipe: the viewers were woken within the pump's step"
        assert only_those_watching
    finally:
        _stop(loop, thread)


def test_news_from_another_thread_wakes_the_viewers_through_the_loop() -> None:
    loop, thread = _loop_in_a_thread()
    try:
        hub = Hub()

        async def join() -> tuple[StreamWatch, asyncio.Event]:
            watch = StreamWatch(asyncio.get_running_loop(), hub)
            return watch, watch.join()

        _watch, viewer = asyncio.run_coroutine_threadsafe(join(), loop).result(5)
        hub.tell()  # from this thread: the event is the loop's, set on the loop

        async def woken() -> bool:
            await asyncio.wait_for(viewer.wait(), 5)
            return True

        assert asyncio.run_coroutine_threadsafe(woken(), loop).result(10)
    finally:
        _stop(loop, thread)
