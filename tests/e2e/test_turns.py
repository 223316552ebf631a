"""Two students on one robot, in two browsers: the turn passes with a countdown; the observer cannot drive."""

from __future__ import annotations

import time

import pytest

from middleware.auth.services import create_user
from middleware.db import session_factory
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer

pytestmark = pytest.mark.e2e
TURN_S = 8


def open_console(page, live_server: LiveServer, username: str) -> None:
    page.goto(f"{live_server.url}/login")
    page.fill("#username", username)
    page.fill("#password", STUDENT_PASSWORD)
    page.get_by_role("button", name="Log in").click()
    page.goto(f"{live_server.url}/lab/lab-1")
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for()


def speed(page) -> float:
    text = page.locator('#console [data-field="linear"]').text_content() or ""
    return float(text) if text.strip() not in {"", "—"} else 0.0


def test_the_turn_passes_between_two_students_and_the_observer_cannot_drive(
    app, live_server: LiveServer, chromium, page
) -> None:
    app.config.update(DEFAULT_TURN_LENGTH_S=TURN_S, ACCESS_TICK_S=0.2)
    with session_factory(app)() as session:
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
    first = page
    open_console(first, live_server, "student1")
    first.locator('queue-panel[data-role="controller"]').wait_for()
    assert "no time limit" in first.locator('[data-field="queue-summary"]').text_content()

    second_context = chromium.new_context(viewport={"width": 390, "height": 844})
    second = second_context.new_page()
    try:
        open_console(second, live_server, "student2")
        second.locator('queue-panel[data-role="waiting"]').wait_for()
        summary = second.locator('[data-field="queue-summary"]').text_content() or ""
        assert "student1 is driving. You are next." in summary, summary
        waiting = second.locator('[data-field="queue-size"]').text_content()
        assert waiting == "1", f"the figure beside 'You are next' counts {waiting} waiting"
        assert second.locator('[data-field="drive-observing"]').is_visible()
        first.locator('#console [data-field="turn-remaining"]').filter(has_text=":").wait_for()

        second.locator("body").focus()
        second.keyboard.down("ArrowUp")
        time.sleep(1.0)
        assert abs(speed(first)) < 0.02, "the observer's keys moved the robot"
        second.keyboard.up("ArrowUp")
        second.locator('[data-field="drive-error"]').filter(has_text="observing").wait_for(timeout=10_000)

        # The observer's skill panels are read-only (no Activate pressed only to be refused), and say why.
        second.get_by_role("tab", name="Navigate").click()
        go_to_goal = second.locator('skill-panel[data-skill="go_to_goal"]')
        go_to_goal.locator('[data-field="skill-observing"]').wait_for()
        assert go_to_goal.locator('button[data-action="activate"]').is_disabled()
        assert go_to_goal.locator('input[name="goal_x_m"]').is_disabled()
        second.screenshot(path=str(ARTIFACTS_DIR / "turn-observer-skills-phone.png"))
        second.get_by_role("tab", name="Drive").click()
        assert second.locator('[data-field="turn-notice"]').is_hidden()

        second.locator('queue-panel[data-role="controller"]').wait_for(timeout=(TURN_S + 5) * 1000)
        first.locator('queue-panel[data-role="waiting"]').wait_for(timeout=5000)
        assert "student2 is driving" in first.locator('[data-field="queue-summary"]').text_content()
        # The turn starting is announced above every tab; the one whose turn ended gets no such notice.
        notice = second.locator('[data-field="turn-notice"]')
        notice.wait_for()
        assert "your turn" in (notice.text_content() or "")
        assert first.locator('[data-field="turn-notice"]').is_hidden()
        second.get_by_role("tab", name="Navigate").click()
        assert second.locator('skill-panel[data-skill="go_to_goal"] button[data-action="activate"]').is_enabled()
        second.get_by_role("tab", name="Drive").click()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        second.screenshot(path=str(ARTIFACTS_DIR / "turn-passed-phone.png"), full_page=True)
        first.screenshot(path=str(ARTIFACTS_DIR / "turn-passed-desktop.png"))

        second.locator("body").focus()
        second.keyboard.down("ArrowUp")
        deadline = time.monotonic() + 3
        while speed(second) < 0.05 and time.monotonic() < deadline:
            time.sleep(0.05)
        second.keyboard.up("ArrowUp")
        assert speed(second) >= 0.05, "the new controller could not drive"
    finally:
        second_context.close()
