"""A student's first session on the console, in Chromium against the real three tiers, at desktop (1280x800) and
phone (390x844) sizes: the console is in tabs, each view fits a screen (camera and drive pad visible together),
chat shows an unread badge on its tab, and the tabs work from the keyboard."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.e2e.test_panels import odometry, open_console, wait_for_control

pytestmark = pytest.mark.e2e
SIZES = {"desktop": (1280, 800), "phone": (390, 844)}


def fully_on_screen(page, selector: str) -> bool:
    """Whether the element is inside the viewport as the page first shows it, without scrolling."""
    return page.locator(selector).first.evaluate(
        "(el) => { const r = el.getBoundingClientRect();"
        " return r.width > 0 && r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight && r.right <= innerWidth; }")


@pytest.mark.parametrize("size", SIZES)
def test_the_first_session_shows_camera_and_drive_pad_together_in_tabs(chromium, live_server: LiveServer,
                                                                       size: str) -> None:
    width, height = SIZES[size]
    context = chromium.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        open_console(page, live_server)
        wait_for_control(page)
        tabs = page.get_by_role("tab")
        assert tabs.all_inner_texts() == ["Drive", "Navigate", "Sense", "Chat"]
        assert page.get_by_role("tab", name="Drive").get_attribute("aria-selected") == "true"
        assert page.evaluate("scrollY") == 0
        page.screenshot(path=str(ARTIFACTS_DIR / f"console-first-screen-{size}.png"))
        for selector in ("camera-panel canvas", 'drive-pad [data-drive="forward"]', 'drive-pad [data-drive="left"]',
                         'drive-pad [data-drive="right"]', 'drive-pad [data-drive="backward"]'):
            assert fully_on_screen(page, selector), f"{selector} is not on the first screen at {size} size"
        assert page.evaluate("document.documentElement.scrollWidth") <= width, "the page scrolls sideways"
        assert page.locator("map-panel").is_hidden() and page.locator("chat-panel").is_hidden()

        # The header fits: on a phone its links are behind "Menu", not cut off at the edge.
        header = page.locator(".site-header")
        assert header.evaluate("(el) => el.scrollWidth <= el.clientWidth"), "the header is cut off"
        bookings = page.get_by_role("link", name="Bookings")
        if size == "phone":
            assert bookings.is_hidden()
            page.get_by_text("Menu", exact=True).click()
            page.screenshot(path=str(ARTIFACTS_DIR / "console-phone-menu.png"))
        assert bookings.is_visible() and fully_on_screen(page, 'a.account__link[href="/experiment"]')
        if size == "phone":
            page.get_by_text("Menu", exact=True).click()

        page.get_by_role("tab", name="Navigate").click()
        assert page.locator("camera-panel").is_hidden()
        assert fully_on_screen(page, 'map-panel [data-field="map-canvas"]') or size == "phone", "map off screen"
        page.locator('skill-panel[data-skill="go_to_goal"]').wait_for()
        page.screenshot(path=str(ARTIFACTS_DIR / f"console-navigate-{size}.png"))
        page.screenshot(path=str(ARTIFACTS_DIR / f"console-navigate-whole-{size}.png"), full_page=True)
        navigate_px = page.evaluate("document.documentElement.scrollHeight")
        skills = page.locator("skill-panel").count()
        print(f"Navigate tab at {size}: {navigate_px} px tall, {skills} skill panels")
        # Seven skills, the map and the 3D view: 4 300 px on a desktop and 5 950 on a phone before their less used
        # settings and long help folded (issue 34, item 18), then at most 3.5 screens and 5 screens; the room camera
        # (issue 33) adds its view: at most 4 screens and 5.5.
        assert skills == 7 and navigate_px <= {"desktop": 3200, "phone": 4650}[size], navigate_px
        go = page.locator('skill-panel[data-skill="go_to_goal"]')
        assert go.locator('input[name="goal_x_m"]').is_visible() and go.locator('input[name="speed_mps"]').is_hidden()
        # A refusal naming a folded field opens the settings, so its sentence is seen beside the field.
        go.evaluate("""(panel) => { panel.error = { code: "invalid_field", field: "timeout_s",
          message: "timeout_s must be at most 1800." }; }""")
        assert go.locator('[data-field-error="timeout_s"]').is_visible() and go.locator(
            'input[name="speed_mps"]').is_visible()

        # The tabs work from the keyboard: arrows move between them.
        page.get_by_role("tab", name="Navigate").focus()
        page.keyboard.press("ArrowRight")
        assert page.get_by_role("tab", name="Sense").get_attribute("aria-selected") == "true"
        page.locator("sonar-panel").wait_for()
        page.keyboard.press("ArrowLeft")
        page.keyboard.down("ArrowLeft")  # held: had the drive pad taken it too, the robot would turn now
        page.wait_for_timeout(800)
        turn_rate = odometry(page, "angular")
        page.keyboard.up("ArrowLeft")
        assert page.get_by_role("tab", name="Drive").get_attribute("aria-selected") == "true"
        assert abs(turn_rate) < 0.05, f"arrow keys on the tabs turned the robot ({turn_rate} rad/s)"
    finally:
        context.close()
    assert not errors, errors


def test_chat_from_someone_else_shows_an_unread_badge_until_the_chat_tab_is_opened(
        app, chromium, page, live_server: LiveServer) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(app)() as session:
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
    open_console(page, live_server)
    badge = page.locator('[role="tab"][data-tab="chat"] [data-field="unread"]')
    assert badge.is_hidden()
    other_context = chromium.new_context(viewport={"width": 390, "height": 844})
    other = other_context.new_page()
    try:
        open_console(other, live_server, "student2")
        other.get_by_role("tab", name="Chat").click()
        other.locator("#chat-input:enabled").fill("Hello from the other student")
        other.get_by_role("button", name="Send").click()
        badge.filter(has_text="1").wait_for()
        page.screenshot(path=str(ARTIFACTS_DIR / "console-chat-unread.png"))
        page.get_by_role("tab", name="Chat").click()
        assert badge.is_hidden(), "the badge stays after the chat was opened"
        page.locator("chat-panel").get_by_text("Hello from the other student").wait_for()
    finally:
        other_context.close()
