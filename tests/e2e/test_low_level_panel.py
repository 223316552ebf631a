"""The Low-level commands panel in Debian's Chromium against the real three tiers: the student reads the battery,
changes the speed ceiling with the keyboard, hears the server's verdict next to the field, and the panel fits a
phone."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console, show_tab_of, wait_for_control

pytestmark = pytest.mark.e2e


def test_the_student_lowers_the_speed_ceiling_in_the_panel_and_reads_its_answer(
        page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    show_tab_of(page, "low-level")
    panel = page.locator("low-level-panel")
    panel.locator('[data-current="max_linear_mps"]').filter(has_text="0.50").wait_for()
    panel.locator('[data-field="battery"]').filter(has_text="%").wait_for()
    assert 0.0 < float(panel.locator('[data-field="battery-meter"]').evaluate("(meter) => meter.value")) <= 1.0
    watchdog = panel.locator('input[name="watchdog_s"]')
    assert watchdog.is_disabled(), "a student in no course may not change the watchdog"
    speed = panel.locator('input[name="max_linear_mps"]')
    assert not speed.is_disabled() and panel.locator('[data-field="limits-observing"]').is_hidden()

    speed.focus()
    page.keyboard.type("0.9")
    page.keyboard.press("Enter")
    error = panel.locator('[data-field-error="max_linear_mps"]')
    error.wait_for()
    assert "max_linear_mps" in error.text_content() and "0.5" in error.text_content()
    assert speed.get_attribute("aria-invalid") == "true"
    assert error.get_attribute("id") in (speed.get_attribute("aria-describedby") or "").split()

    speed.fill("0.3")
    page.keyboard.press("Enter")
    panel.locator('[data-field="limits-answer"]').filter(has_text="Saved").wait_for()
    panel.locator('[data-current="max_linear_mps"]').filter(has_text="0.30").wait_for()
    assert speed.get_attribute("aria-invalid") is None and speed.input_value() == ""
    answer = page.evaluate("fetch('/api/robots/lab-1/limits').then((r) => r.json())")
    assert answer["limits"]["max_linear_mps"] == 0.3, "the robot itself holds the new ceiling"

    page.set_viewport_size({"width": 390, "height": 844})
    show_tab_of(page, "low-level")
    assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the console scrolls sideways on a phone"
    box = panel.bounding_box()
    assert box is not None and box["width"] <= 390
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    panel.screenshot(path=str(ARTIFACTS_DIR / "low-level-panel-phone.png"))
    speed.fill("0.5")
    page.keyboard.press("Enter")
    panel.locator('[data-current="max_linear_mps"]').filter(has_text="0.50").wait_for()


def test_an_observer_sees_the_settings_read_only(app, live_server: LiveServer, chromium, page) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from tests.conftest import STUDENT_PASSWORD

    with session_factory(app)() as session:
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
    open_console(page, live_server, "student1")
    wait_for_control(page)
    second_context = chromium.new_context(viewport={"width": 390, "height": 844})
    second = second_context.new_page()
    try:
        open_console(second, live_server, "student2")
        second.locator('queue-panel[data-role="waiting"]').wait_for()
        show_tab_of(second, "low-level")
        panel = second.locator("low-level-panel")
        panel.locator('[data-field="limits-observing"]').wait_for()
        panel.locator('[data-current="max_linear_mps"]').filter(has_text="0.").wait_for()
        assert panel.locator('input[name="max_linear_mps"]').is_disabled()
        assert panel.locator('button[data-action="save-limits"]').is_disabled()
    finally:
        second_context.close()
