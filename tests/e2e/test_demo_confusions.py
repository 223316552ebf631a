"""Issue 34's confusions on the demo course's tests, clicked through in Chromium from what `telelab up` seeds: a bare
number answers a numeric question in its own unit (item 9); the Tests page shows the tutor's override (item 10);
the experimental task states its goal once (item 19); the demo tutor sees the survey's charts (item 17).
Screenshots in test-artifacts/."""

from __future__ import annotations

import re

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_demo_journeys import open_header_link

pytestmark = pytest.mark.e2e


def _seed(app) -> None:
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)


def _log_in(chromium, live_server: LiveServer, name: str, password: str):
    page = chromium.new_context(viewport={"width": 1280, "height": 800}).new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill(name)
    page.get_by_label("Password").fill(password)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()
    return page, errors


def test_a_bare_number_is_an_answer_and_the_tests_page_shows_the_tutor_s_mark(
        chromium, app, demo_accounts, live_server: LiveServer) -> None:
    from middleware.demo_course import EXPERIMENTAL_TITLE, TIMED_TITLE

    _seed(app)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    student, errors = _log_in(chromium, live_server, "student", demo_accounts["student"])
    open_header_link(student, "Tests")
    student.get_by_role("link", name=TIMED_TITLE).click()
    student.get_by_role("button", name="Start").click()
    student.get_by_label("The wheels slip and their measured turns carry small errors that add up").check()
    student.get_by_label("Value").fill("8")
    student.get_by_label("Unit").fill("")  # a bare number: the question's own unit, as the page says
    student.get_by_label("Unit").press("Tab")
    numeric = student.locator("fieldset", has_text="laser's maximum range")
    assert numeric.locator('[data-field="unit-note"]').text_content() == "A number without a unit is read in m."
    student.get_by_label("The lab's map").check()
    student.get_by_label("Your answer").fill("wall following")
    student.get_by_label("Your answer").press("Tab")
    student.screenshot(path=str(ARTIFACTS_DIR / "demo-bare-number-desktop.png"), full_page=True)
    student.get_by_role("button", name="Submit").click()
    student.locator("#score").wait_for()  # submitted at the first press: nothing is called "not answered"
    assert student.locator("#unanswered").is_hidden()
    assert student.locator("#score strong").text_content() == "4"
    assert "Correct (8 ± 0.5 m)." in numeric.locator("[data-result]").text_content()
    attempt_url = student.url

    tutor, tutor_errors = _log_in(chromium, live_server, "tutor", demo_accounts["tutor"])
    tutor.goto(attempt_url)
    tutor.get_by_label("Item").select_option(label="Question 2 (1/1)")
    tutor.get_by_label("New mark").fill("0.5")
    tutor.get_by_label("Reason (the student sees it)").fill("Say which sensor you mean")
    tutor.get_by_role("button", name="Change the mark").click()
    tutor.locator(".flash--success", has_text="Mark changed.").wait_for()

    student.goto(attempt_url)
    assert student.locator("#score strong").text_content() == "3.5"
    open_header_link(student, "Tests")
    listed = student.locator("li", has=student.get_by_role("link", name=TIMED_TITLE))
    assert re.search(r"attempt 1: 3\.5/4\b", listed.text_content()), listed.text_content()
    student.screenshot(path=str(ARTIFACTS_DIR / "demo-tests-after-override-desktop.png"), full_page=True)
    student.get_by_role("link", name=TIMED_TITLE).click()
    assert student.locator('[data-field="mark"]').text_content() == "3.5/4"

    open_header_link(student, "Tests")
    student.get_by_role("link", name=EXPERIMENTAL_TITLE).click()
    task = student.locator("section.card").first.text_content()
    assert task.count("(1.5, 1.5)") == 1 and task.count("then submit") == 1, task
    student.screenshot(path=str(ARTIFACTS_DIR / "demo-experimental-task-desktop.png"), full_page=True)

    tutor.goto(f"{live_server.url}/assessment")
    tutor.get_by_role("link", name="Survey results").click()
    tutor.locator("#survey-chart").wait_for()
    assert tutor.locator("#survey-hidden").count() == 0
    assert "Booking a slot was hard" in tutor.locator("#survey-comments").text_content()
    tutor.screenshot(path=str(ARTIFACTS_DIR / "demo-survey-charts-desktop.png"), full_page=True)
    student.context.close()
    tutor.context.close()
    assert not errors and not tutor_errors, errors + tutor_errors
