"""A tutor diagnoses and recovers a lab robot from the web in Debian's Chromium: from the robots page to the robot's
health, reads it, sends it to its dock, restarts it after confirming, and sees it answer again with the restart
and both actions in its maintenance log; the page at phone size."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD
from tests.e2e.test_console import log_in
from tests.integration.lab.test_robot_health import lab, robot_process  # noqa: F401 - fixtures

pytestmark = pytest.mark.e2e


def test_a_tutor_reads_a_robots_health_docks_and_restarts_it_and_reads_the_log(page, lab) -> None:  # noqa: F811
    log_in(page, lab, "tutor1", STUDENT_PASSWORD)
    page.goto(f"{lab.url}/lab")
    page.get_by_role("link", name="Health and recovery of lab-1").click()
    page.locator('[data-field="real-time-factor"]').wait_for()
    assert page.locator('[data-field="online"]').text_content() == "lab-1 answers."
    assert page.locator('[data-field="restarts"]').text_content() == "0"
    page.get_by_role("button", name="Return to dock").click()
    page.locator('[data-field="action-result"]', has_text="back at its dock").wait_for()
    page.get_by_role("button", name="Restart robot").click()
    page.get_by_role("button", name="Yes, restart it").click()
    page.locator('[data-field="action-result"]', has_text="is restarting").wait_for()
    page.locator('[data-field="restarts"]', has_text="1").wait_for(timeout=30_000)
    entries = page.locator('[data-slot="maintenance"] li')
    assert entries.count() == 2
    assert "tutor1: lab-1 is restarting" in (entries.nth(0).text_content() or "")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-health-desktop.png"), full_page=True)
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-health-phone.png"), full_page=True)
