"""Logout ends the login in another browser holding the same cookie; an admin clears a login throttle."""

from __future__ import annotations

from datetime import timedelta

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e


def _log_in(tab, live_server: LiveServer, username: str, password: str = STUDENT_PASSWORD) -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", password)
    tab.get_by_role("button", name="Log in").click()


def test_logout_ends_the_session_in_a_second_browser_sharing_the_cookie(chromium, page,
                                                                         live_server: LiveServer) -> None:
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    _log_in(page, live_server, "student1")
    page.locator('[data-field="username"]').wait_for()
    copy_context = chromium.new_context(viewport={"width": 1280, "height": 800})
    try:
        copy_context.add_cookies(page.context.cookies())
        copy = copy_context.new_page()
        copy.goto(f"{live_server.url}/account/password")
        assert copy.url.endswith("/account/password"), "the copied cookie opens the login before logout"
        page.get_by_role("button", name="Log out").click()
        page.wait_for_url("**/login")
        copy.goto(f"{live_server.url}/account/password")
        assert "/login?next=" in copy.url, copy.url
        assert copy.get_by_role("button", name="Log in").is_visible()
        copy.screenshot(path=str(ARTIFACTS_DIR / "sessions-copied-cookie-after-logout.png"), full_page=True)
    finally:
        copy_context.close()


def test_an_admin_clears_a_throttle_and_the_slowed_login_works_again(chromium, page, live_server: LiveServer,
                                                                      course_people, monkeypatch) -> None:  # noqa: F811
    from middleware.auth import throttle

    # A first delay of ten minutes, so the slowed state outlasts a loaded machine's clicks.
    monkeypatch.setattr(throttle, "PER_ACCOUNT_AND_ADDRESS",
                        throttle.DelayRule(3, timedelta(minutes=10), timedelta(minutes=15)))
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    guesser_context = chromium.new_context(viewport={"width": 1280, "height": 800})
    try:
        guesser = guesser_context.new_page()
        for _ in range(3):
            _log_in(guesser, live_server, "student2", "not-the-password")
            guesser.get_by_text("Wrong username or password").wait_for()
        _log_in(guesser, live_server, "student2")
        guesser.get_by_text("Too many failed attempts from here; try again in 10 minutes.").wait_for()

        _log_in(page, live_server, "admin1")
        page.locator('[data-field="username"]').wait_for()
        page.goto(f"{live_server.url}/admin/users")
        row = page.locator('#throttle-list tr[data-throttle-username="student2"]')
        assert "127.0.0.1" in row.text_content() and "3" in row.locator('[data-label="Failures"]').text_content()
        page.locator("#throttles").screenshot(path=str(ARTIFACTS_DIR / "throttles-admin-section.png"))
        row.get_by_role("button", name="Clear the throttle of student2 from 127.0.0.1").click()
        page.get_by_text("Cleared 3 failed logins of student2 from 127.0.0.1.").wait_for()
        assert page.locator("#throttle-list-empty").is_visible()
        page.screenshot(path=str(ARTIFACTS_DIR / "throttles-cleared.png"), full_page=True)

        _log_in(guesser, live_server, "student2")
        guesser.locator('[data-field="username"]').wait_for()
    finally:
        guesser_context.close()
