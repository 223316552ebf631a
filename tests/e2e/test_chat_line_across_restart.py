"""A chat line sent while the server's 1012 (a rolling restart) is on its way is not lost, in Debian's Chromium: the
sender's link is routed so that the line reaches the server only after the server has closed every socket with 1012
(it is never read, as on a leaving worker); the line shows as sending until the server serves again, is sent again
on the new link, and both the sender and another student read it once."""

from __future__ import annotations

import contextlib
import json
import time

import pytest
from sqlalchemy import func, select

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_chat_and_bookings import open_chat
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e
LINE = "sent as the server restarts"
BODIES = 'chat-panel [data-field="chat-body"]'


def _is_say(frame: str) -> bool:
    _, _, text = frame.partition(" ")
    try:
        return json.loads(text).get("type") == "say"
    except (ValueError, AttributeError):
        return False


def say(tab, line: str) -> None:
    """Writes line in the chat and presses Enter, as a person does."""
    tab.get_by_label("Message to everyone on this robot").fill(line)
    tab.keyboard.press("Enter")


def _stored_copies(app, body: str) -> int:
    from middleware.db import session_factory
    from middleware.models import ChatMessage

    with session_factory(app)() as session:
        return session.scalar(select(func.count()).select_from(ChatMessage).where(ChatMessage.body == body))


def _restart_under(server, frame: str, held: list[str]) -> None:
    """Closes every socket of the server with 1012 (a leaving worker), then lets the line reach it: never read. The
    server refuses new sockets (1012) until the test lets the new worker serve."""
    from middleware.live.loop import channel_loop, drain_channels

    drain_channels()
    deadline = time.monotonic() + 10
    while channel_loop().open_sockets and time.monotonic() < deadline:
        time.sleep(0.02)
    held.append((frame, channel_loop().open_sockets))
    with contextlib.suppress(Exception):  # the connection is closed already: the line is lost to the server either way
        server.send(frame)


def test_a_line_sent_as_the_server_closes_with_1012_is_sent_again_and_stored_once(
        chromium, page, live_server: LiveServer, course_people) -> None:  # noqa: F811
    from middleware.live.loop import channel_loop

    other_context = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    other = other_context.new_page()
    held: list[str] = []
    restarted = False

    def route(socket) -> None:
        server = socket.connect_to_server()

        def outbound(frame) -> None:
            nonlocal restarted
            if isinstance(frame, str) and _is_say(frame) and not restarted:
                restarted = True
                _restart_under(server, frame, held)
            else:
                server.send(frame)

        socket.on_message(outbound)

    try:
        page.route_web_socket("**/ws/link", route)
        open_chat(page, live_server, "student1")
        open_chat(other, live_server, "student2")
        say(page, LINE)
        sending = page.locator("chat-panel .chat__item--pending", has_text=LINE)
        sending.locator('[data-field="chat-status"]', has_text="Sending").wait_for(timeout=15000)
        assert [sockets for _, sockets in held] == [0], "the line did not go out after every socket had closed"
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.locator("chat-panel").screenshot(path=str(ARTIFACTS_DIR / "chat-line-sending.png"))
        channel_loop().draining = False  # the new worker serves

        for tab in (page, other):
            tab.locator(BODIES, has_text=LINE).first.wait_for(timeout=30000)
        time.sleep(1.5)  # a second copy would have come by now
        for tab in (page, other):
            assert tab.locator(BODIES, has_text=LINE).count() == 1
            assert tab.locator("chat-panel .chat__item--pending").count() == 0
        assert _stored_copies(live_server.app, LINE) == 1
        page.locator("chat-panel").screenshot(path=str(ARTIFACTS_DIR / "chat-line-after-restart.png"))
    finally:
        channel_loop().draining = False
        other_context.close()


def test_a_line_cut_off_by_another_close_waits_as_not_sent_until_the_person_sends_it_again(
        page, live_server: LiveServer, course_people) -> None:  # noqa: F811
    """After a close other than 1012 nobody knows whether the server read the line: it is not sent again by itself
    (it might be stored twice); the person sees it as not sent and sends it again with one click."""
    cut = []

    def route(socket) -> None:
        server = socket.connect_to_server()

        def outbound(frame) -> None:
            if isinstance(frame, str) and _is_say(frame) and not cut:
                cut.append(frame)
                socket.close(code=1011, reason="the connection broke")
            else:
                server.send(frame)

        socket.on_message(outbound)

    page.route_web_socket("**/ws/link", route)
    open_chat(page, live_server, "student1")
    say(page, LINE)

    unsent = page.locator("chat-panel .chat__item--unsent", has_text=LINE)
    unsent.locator('[data-field="chat-status"]', has_text="Not sent").wait_for(timeout=15000)
    page.locator("#chat-input:enabled").wait_for(timeout=15000)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.locator("chat-panel").screenshot(path=str(ARTIFACTS_DIR / "chat-line-not-sent.png"))
    unsent.get_by_role("button", name="Send again").click()
    page.locator(BODIES, has_text=LINE).wait_for(timeout=15000)
    assert page.locator("chat-panel .chat__item--pending").count() == 0
    assert _stored_copies(live_server.app, LINE) == 1
