"""Two students chat on the console, and one books a slot on the bookings page, in Debian's Chromium."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e
HOSTILE = "<img src=x onerror=alert(1)>"


def log_in(tab, live_server: LiveServer, username: str) -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def open_chat(tab, live_server: LiveServer, username: str) -> None:
    """Logs username in on tab and opens lab-1's console on its Chat tab, ready to send."""
    log_in(tab, live_server, username)
    tab.goto(f"{live_server.url}/lab/lab-1")
    tab.get_by_role("tab", name="Chat").click()
    tab.locator("#chat-input:enabled").wait_for(timeout=15000)


def test_two_students_chat_and_one_books_a_slot(chromium, page, live_server: LiveServer, course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    other_context = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    other = other_context.new_page()
    errors: list[str] = []
    other.on("pageerror", lambda error: errors.append(str(error)))
    dialogs: list[str] = []
    for tab in (page, other):
        tab.on("dialog", lambda dialog: (dialogs.append(dialog.message), dialog.dismiss()))
    try:
        open_chat(page, live_server, "student1")
        open_chat(other, live_server, "student2")
        page.get_by_label("Message to everyone on this robot").fill(HOSTILE)
        page.keyboard.press("Enter")
        received = other.locator('chat-panel [data-field="chat-body"]', has_text=HOSTILE)
        received.wait_for(timeout=15000)
        assert received.text_content() == HOSTILE
        assert other.locator("chat-panel img").count() == 0 and dialogs == []
        other.get_by_label("Message to everyone on this robot").fill("hello from my phone")
        other.get_by_role("button", name="Send").click()
        page.locator('chat-panel [data-field="chat-body"]', has_text="hello from my phone").wait_for(timeout=15000)
        other.locator("chat-panel").scroll_into_view_if_needed()
        other.screenshot(path=str(ARTIFACTS_DIR / "chat-phone.png"))
        page.locator("chat-panel").screenshot(path=str(ARTIFACTS_DIR / "chat-desktop.png"))

        page.get_by_role("link", name="Bookings").click()
        page.locator("#bookings").wait_for()
        assert page.locator("#time-zone").text_content() == page.evaluate(
            "Intl.DateTimeFormat().resolvedOptions().timeZone")
        page.get_by_role("link", name="Next week →").click()
        page.locator("button.slot--free").first.click()
        page.locator(".flash--success").wait_for()
        assert "Booked lab-1" in page.locator(".flash--success").text_content()
        assert page.locator("#my-bookings li").count() == 1
        page.screenshot(path=str(ARTIFACTS_DIR / "bookings-desktop.png"), full_page=False)
        other.goto(f"{live_server.url}/bookings?tz=Europe/Madrid")
        other.screenshot(path=str(ARTIFACTS_DIR / "bookings-phone.png"))
        assert other.locator("#time-zone").text_content() == "Europe/Madrid"
        # The console's turn panel lists the robot's next bookings: the booker sees it as theirs.
        for tab, whose in ((page, "yours"), (other, "booked")):
            tab.goto(f"{live_server.url}/lab/lab-1")
            listed = tab.locator('queue-panel [data-field="robot-bookings"] li').first
            listed.wait_for(timeout=15000)
            assert listed.text_content().endswith(whose), listed.text_content()
        other.locator("queue-panel").scroll_into_view_if_needed()
        other.screenshot(path=str(ARTIFACTS_DIR / "console-bookings-phone.png"))
    finally:
        other_context.close()
    assert not errors, errors
