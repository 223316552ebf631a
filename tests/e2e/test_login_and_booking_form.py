"""Issue 34, item 19, in Chromium: a disabled account is told so (only when its password is right), and the booking
form's "any robot" checkbox sits beside its label at desktop and phone size. Screenshots in test-artifacts/."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, served_lab
from tests.e2e.test_chat_and_bookings import log_in

pytestmark = pytest.mark.e2e
SIZES = {"desktop": {"width": 1280, "height": 800}, "phone": {"width": 390, "height": 844}}


def _try_login(page, live_server: LiveServer, password: str) -> str:
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill("student1")
    page.get_by_label("Password").fill(password)
    page.get_by_role("button", name="Log in").click()
    return page.get_by_role("alert").text_content().strip()


def test_a_disabled_account_is_told_it_is_disabled_not_that_its_password_is_wrong(
        page, live_server: LiveServer) -> None:
    from middleware.accounts.services import set_active_by_name
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        set_active_by_name(session, "student1", False)
        session.commit()
    assert _try_login(page, live_server, STUDENT_PASSWORD) == (
        "This account is disabled. Ask your tutor or the lab's administrator to enable it again.")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "login-disabled-account-desktop.png"))
    # Without the password, nothing about the account is given away.
    assert _try_login(page, live_server, "not-the-password") == "Wrong username or password. Check both and try again."
    assert page.url.endswith("/login")


@pytest.fixture
def pool_of_two(tmp_path) -> Iterator[LiveServer]:
    """Two robots of one kind (sim): the booking form offers "any sim robot". Nothing needs to answer on port 9."""
    with served_lab("sim-1=127.0.0.1:9,sim-2=127.0.0.1:9", tmp_path) as server:
        yield server


@pytest.mark.parametrize("size", list(SIZES))
def test_the_any_robot_checkbox_sits_beside_its_label(chromium, pool_of_two: LiveServer, size: str) -> None:
    phone = size == "phone"
    context = chromium.new_context(viewport=SIZES[size], is_mobile=phone, has_touch=phone)
    page = context.new_page()
    try:
        log_in(page, pool_of_two, "student1")
        page.goto(f"{pool_of_two.url}/bookings?robot=sim-1")
        box = page.get_by_role("checkbox", name="Any sim robot (2 alike), assigned when the slot starts")
        label = page.locator('label[for="booking-pool"]')
        box.scroll_into_view_if_needed()
        check, words = box.bounding_box(), label.bounding_box()
        assert check is not None and words is not None
        assert check["x"] + check["width"] <= words["x"], (check, words)  # before the label, on its line
        assert words["y"] <= check["y"] + check["height"] / 2 <= words["y"] + words["height"], (check, words)
        assert check["height"] <= 32, check  # a box, not a 44 px text field
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.locator(".booking-form__fields").screenshot(path=str(ARTIFACTS_DIR / f"booking-any-robot-{size}.png"))
        label.click()  # the label ticks it, as a person expects
        assert box.is_checked()
    finally:
        context.close()
