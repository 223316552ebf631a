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
LINES = ["read before the restart", "sent as the server restarts", "and one more right after"]
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


def _wait_until(condition, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.02)


def _write_at_once(tab, lines: list[str]) -> None:
    """Submits the lines in one task of the page, so that all of them leave before the page can see a close."""
    tab.evaluate("""(lines) => {
        const input = document.querySelector("#chat-input");
        for (const line of lines) { input.value = line; input.form.requestSubmit(); }
    }""", lines)


def test_lines_sent_as_the_server_closes_with_1012_are_sent_again_and_each_stored_once(
        chromium, page, live_server: LiveServer, course_people) -> None:  # noqa: F811
    """The first line reaches the server before its restart and is answered (it must not go again); the next two
    reach it only after every socket has closed with 1012 (never read: they must go again)."""
    from middleware.live.loop import channel_loop, drain_channels

    other_context = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    other = other_context.new_page()
    says: list[str] = []
    open_after_drain: list[int] = []
    connections: list[object] = []

    def route(socket) -> None:
        server = socket.connect_to_server()
        first = not connections
        connections.append(socket)

        def outbound(frame) -> None:
            if not (first and isinstance(frame, str) and _is_say(frame)):
                server.send(frame)
                return
            says.append(frame)
            if len(says) > 1:  # the server closed every socket already: this line is never read
                with contextlib.suppress(Exception):
                    server.send(frame)
                return
            server.send(frame)
            _wait_until(lambda: _stored_copies(live_server.app, LINES[0]) == 1)
            drain_channels()  # a leaving worker: it answers the line it read, then closes with 1012
            _wait_until(lambda: channel_loop().open_sockets == 0)
            open_after_drain.append(channel_loop().open_sockets)

        socket.on_message(outbound)

    try:
        page.route_web_socket("**/ws/link", route)
        open_chat(page, live_server, "student1")
        open_chat(other, live_server, "student2")
        _write_at_once(page, LINES)
        sending = page.locator("chat-panel .chat__item--pending", has_text=LINES[-1])
        sending.locator('[data-field="chat-status"]', has_text="Sending").wait_for(timeout=15000)
        assert len(says) == len(LINES) and open_after_drain == [0], (says, open_after_drain)
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.locator("chat-panel").screenshot(path=str(ARTIFACTS_DIR / "chat-line-sending.png"))
        channel_loop().draining = False  # the new worker serves

        for tab in (page, other):
            tab.locator(BODIES, has_text=LINES[-1]).first.wait_for(timeout=30000)
        time.sleep(1.5)  # a second copy would have come by now
        for tab in (page, other):
            assert [text for text in tab.locator(BODIES).all_text_contents() if text in LINES] == LINES
            assert tab.locator("chat-panel .chat__item--pending").count() == 0
        assert [_stored_copies(live_server.app, line) for line in LINES] == [1] * len(LINES)
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
