"""From the state `telelab up` seeds, the demo student books a slot and finds the quiz, the timed test and the
experimental test, in Chromium at desktop and phone size (issue 14, failure 5). Screenshots in test-artifacts/."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer

pytestmark = pytest.mark.e2e
SIZES = {"desktop": {"width": 1280, "height": 800}, "phone": {"width": 390, "height": 844}}


@pytest.mark.parametrize("size", list(SIZES))
def test_the_demo_student_books_a_slot_and_finds_every_kind_of_test(
        chromium, app, demo_accounts, live_server: LiveServer, size: str) -> None:
    from middleware.demo_course import EXPERIMENTAL_TITLE, QUIZ_TITLE, TIMED_TITLE
    from middleware.lab_runner import seed_demo_course
    from middleware.teaching.demo_content import seed_demo_content

    seed_demo_course(app)  # what `telelab up` seeds after creating the accounts (the lesson's video aside: slow)
    seed_demo_content(app, record_video=False)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    phone = size == "phone"
    context = chromium.new_context(viewport=SIZES[size], is_mobile=phone, has_touch=phone)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(f"{live_server.url}/login")
        page.get_by_label("Username").fill("student")
        page.get_by_label("Password").fill(demo_accounts["student"])
        page.get_by_role("button", name="Log in").click()
        page.locator('[data-field="username"]').wait_for()

        open_header_link(page, "Bookings")
        page.locator("#bookings[data-tz]").wait_for()
        assert "of your 120 minutes" in page.locator('[data-field="allowance"]').text_content()
        # Late on a Sunday this week's free half-hours may all lie inside the 2-h booking below (four of them),
        # leaving none to show as used up by the week's allowance: the next week is booked instead.
        if page.locator("button.slot--free").count() <= 4:
            page.get_by_role("link", name="Next week →").click()
        assert page.locator(".slot--unavailable").count() == 0
        page.get_by_label("Length").select_option(label="2 h")
        slot = page.locator("button.slot--free").first
        slot.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"demo-bookings-free-{size}.png"))
        slot.focus()
        page.keyboard.press("Enter")  # a slot is a button: the keyboard books it as a click does
        page.locator(".flash--success", has_text="Booked lab-1").wait_for()
        assert page.locator("#my-bookings li").count() == 1
        # The week's 120 minutes are used: its other free slots now say so instead of "free".
        unavailable = page.locator(".slot--unavailable")
        assert unavailable.count() > 0 and page.locator("button.slot--free").count() == 0
        assert unavailable.first.text_content().strip().endswith("no minutes left")
        assert "You have booked all 120 minutes" in page.locator("#unavailable-reasons").text_content()
        page.locator("#unavailable-reasons").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"demo-bookings-reason-{size}.png"))
        page.locator(".slot--mine").first.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"demo-bookings-used-{size}.png"))

        open_header_link(page, "Tests")
        page.get_by_role("heading", name="Mobile robotics (demo)").wait_for()
        for title in (QUIZ_TITLE, TIMED_TITLE, EXPERIMENTAL_TITLE):
            assert page.get_by_role("link", name=title).is_visible(), title
        assert page.get_by_role("link", name="Evaluate the lab (8 questions)").count() == 1
        page.screenshot(path=str(ARTIFACTS_DIR / f"demo-tests-{size}.png"), full_page=True)
        page.get_by_role("link", name=TIMED_TITLE).click()
        page.get_by_role("button", name="Start").wait_for()
        page.screenshot(path=str(ARTIFACTS_DIR / f"demo-timed-test-{size}.png"))
    finally:
        context.close()
    assert not errors, errors


def open_header_link(page, name: str) -> None:
    """Follows a link of the site header as a person does: on a phone it is behind the "Menu" button."""
    page.wait_for_load_state("domcontentloaded")  # site-menu.js has folded the menu on a phone by then
    link = page.locator(".site-header").get_by_role("link", name=name)
    if link.is_hidden():
        page.locator(".site-header").get_by_text("Menu", exact=True).click()
    link.click()
