"""The console's former confusions, each clicked through in Chromium against the real three tiers: no safety
warning after a normal key release, an offline robot's turn not shown as "your turn in 0:00", no research
jargon or snake_case words, and a timed run's progress."""

from __future__ import annotations

import re

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console, wait_for, wait_for_control, wait_for_status

pytestmark = pytest.mark.e2e


def test_a_normal_key_release_shows_no_deadman_warning(page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    page.evaluate("document.activeElement.blur()")
    page.keyboard.down("ArrowUp")
    page.wait_for_timeout(600)
    page.keyboard.up("ArrowUp")
    page.wait_for_timeout(1500)  # well past the robot's 0.4 s deadman
    assert page.locator('odometry-panel [data-field="deadman"]').is_hidden(), "a stop was reported as a safety stop"


def test_an_offline_robot_says_so_instead_of_your_turn_in_no_time(page, live_server: LiveServer) -> None:
    open_console(page, live_server, robot="ghost", online=False)
    queue = page.locator("queue-panel")
    queue.locator('[data-field="queue-summary"]').filter(has_text="The robot is not answering").wait_for()
    assert queue.locator('[data-field="estimated-wait"]').text_content() == "—"
    assert "0:00" not in (queue.text_content() or "")
    robot = page.locator('[data-field="robot-connection"]')
    robot.filter(has_text="not answering").wait_for()
    page.screenshot(path=str(ARTIFACTS_DIR / "console-offline-robot.png"))



def test_a_timed_wall_following_run_shows_progress_in_plain_words(page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    page.get_by_role("tab", name="Navigate").click()
    panel = page.locator('skill-panel[data-skill="wall_following"]')
    panel.locator("[data-field=skill-settings] summary").click()  # the fields set less often are folded
    panel.locator('input[name="duration_s"]').fill("6")
    panel.locator('button[data-action="activate"]').click()
    wait_for_status(page, "wall_following", "executing")
    progress = panel.locator("progress")
    wait_for(lambda: float(progress.evaluate("(bar) => bar.value")) > 0.1, 15, "the timed run's progress stays at 0")
    page.locator('skill-panel[data-skill="wall_following"][data-status="succeeded"]').wait_for(timeout=30_000)
    shown = page.locator("#console").inner_text()
    jargon = sorted(set(re.findall(r"\b[a-z]+_[a-z_]+\b", shown)))
    assert not jargon, f"snake_case words on the console: {jargon}"
    assert "thesis" not in shown and not re.search(r"\bframe \d+", shown), "research jargon on the console"
