"""Issue 34, item 12, in Chromium against a course-B robot: during a delay trial the console keeps the student to
driving by hand (go-to-goal is refused with the reason) and shows the motion preview as the trial set it, not as a
switch; a trial given up is shown as given up, not as the trial recorded before it. Screenshots in test-artifacts/."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.e2e.test_console import log_in
from tests.e2e.test_experiment import PHONE, course_b_lab  # noqa: F401 (fixture)
from tests.e2e.test_panels import show_tab_of

pytestmark = pytest.mark.e2e


def _recorded_trial(app) -> None:
    """A trial student1 ran and had recorded before (as the page records one: the robot's time and errors)."""
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.experiment import services

    with session_factory(app)() as session:
        student = find_user(session, "student1")
        trial = services.assign_trial(session, student, "course-b", "course-B")
        services.finish_trial(session, student, trial.id, services.RunResult(42.0, 1))
        session.commit()


def test_a_trial_keeps_the_console_to_driving_by_hand_and_a_trial_given_up_says_so(
        page, course_b_lab: tuple[Any, LiveServer]) -> None:  # noqa: F811
    _robot, lab = course_b_lab
    _recorded_trial(lab.app)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    log_in(page, lab, "student1", STUDENT_PASSWORD)
    page.goto(f"{lab.url}/experiment")
    page.locator('[data-field="last-trial"]', has_text="Trial recorded: 42.0 s, 1 line contact.").wait_for()
    # The console is open before the trial begins: the preview is a switch until then.
    console = page.context.new_page()
    console.goto(f"{lab.url}/lab/course-b")
    console.locator('queue-panel[data-role="controller"]').wait_for()
    toggle = console.locator('[data-field="feedback-toggle"]')
    lock = console.locator('[data-field="feedback-lock"]')
    assert toggle.is_enabled() and lock.is_hidden()

    page.bring_to_front()
    page.get_by_role("button", name="Start the next trial").click()
    page.locator('[data-field="run"]').wait_for()
    trial = json.loads(page.evaluate("fetch('/api/experiment/state').then((r) => r.text())"))["trial"]
    shown = "on" if trial["feedback"] else "off"
    assert f"Motion preview{shown}" in page.locator('[data-field="condition"]').text_content()

    console.bring_to_front()
    lock.wait_for(timeout=10_000)  # the trial's delay reached the open console, and with it the trial's preview
    assert lock.text_content() == f"Your delay trial sets the motion preview {shown} until it is recorded or given up."
    assert toggle.is_disabled() and toggle.is_checked() is (shown == "on")
    console.locator("camera-panel").screenshot(path=str(ARTIFACTS_DIR / "trial-preview-locked-desktop.png"))

    show_tab_of(console, console.locator('skill-panel[data-skill="go_to_goal"]').evaluate(
        "(panel) => panel.closest('section[data-panel-id]').dataset.panelId"))
    go = console.locator('skill-panel[data-skill="go_to_goal"]')
    go.locator('input[name="goal_x_m"]').fill("3.0")
    go.locator('input[name="goal_y_m"]').fill("1.5")
    go.locator('button[data-action="activate"]').click()
    refusal = go.locator('[data-field="skill-error"]')
    refusal.wait_for()
    assert refusal.text_content().startswith("Your delay trial on course-b measures driving by hand: go-to-goal")
    assert go.get_attribute("data-status") not in ("executing", "succeeded")
    go.screenshot(path=str(ARTIFACTS_DIR / "trial-go-to-goal-refused-desktop.png"))
    console.close()

    page.get_by_role("button", name="Give up this trial").click()
    banner = page.locator('[data-field="last-trial"]')
    banner.filter(has_text="Trial given up").wait_for()
    assert "recorded" not in banner.text_content() and banner.get_attribute("data-status") == "abandoned"
    assert page.get_by_role("button", name="Start a trial").is_visible()
    page.screenshot(path=str(ARTIFACTS_DIR / "trial-given-up-desktop.png"), full_page=True)
    page.set_viewport_size(PHONE)
    page.screenshot(path=str(ARTIFACTS_DIR / "trial-given-up-phone.png"), full_page=True)


def test_a_student_of_two_courses_chooses_the_course_a_trial_counts_for(
        page, course_b_lab: tuple[Any, LiveServer]) -> None:  # noqa: F811
    from tests.conftest import make_course

    _robot, lab = course_b_lab  # student1 is in EXP already
    other = make_course(lab.app, "ZZ", {"student1": "student"})
    page.set_viewport_size(PHONE)
    log_in(page, lab, "student1", STUDENT_PASSWORD)
    page.goto(f"{lab.url}/experiment")
    choice = page.get_by_label("Counts for")
    choice.wait_for()  # drawn once the page has read the state
    assert choice.locator("option").all_text_contents() == ["EXP — Course EXP", "ZZ — Course ZZ"]
    choice.select_option(label="ZZ — Course ZZ")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "trial-course-choice-phone.png"), full_page=True)
    page.get_by_role("button", name="Start a trial").click()
    page.locator('[data-field="run"]').wait_for()
    trial = json.loads(page.evaluate("fetch('/api/experiment/state').then((r) => r.text())"))["trial"]
    assert trial["course_id"] == other
    page.get_by_role("button", name="Give up this trial").click()
    page.locator('[data-field="last-trial"]', has_text="Trial given up").wait_for()
