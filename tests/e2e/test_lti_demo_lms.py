"""The demo LMS that `make run` starts beside the lab (middleware/lti/demo_lms.py), walked in Chromium as a person
trying Telelab's LTI does: its course page launches its learner into Telelab inside the frame, who opens lab-1's
console; its instructor places the demo course's practice quiz by deep linking; the learner takes the placed quiz
and the LMS's gradebook shows the grade Telelab passed back; on a phone, a launch in Spanish opens Telelab in
Spanish.

The lab is the test's served app (with lab-1); the demo LMS is started, registered and linked to the demo course by
the same functions `telelab up` calls (lab_runner.start_demo_lms), as a child process."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer, served_lab
from tests.e2e.test_panels import wait_for

pytestmark = pytest.mark.e2e

QUIZ = "Practice quiz: sensors and odometry"


@pytest.fixture
def demo(skill_server_address: str, tmp_path: Path) -> Iterator[tuple[LiveServer, str]]:
    """The lab with the demo accounts and course, and the demo LMS beside it: (server, the LMS's address)."""
    from middleware.lab_runner import ensure_demo_accounts, seed_demo_course, start_demo_lms

    with served_lab(f"lab-1={skill_server_address}", tmp_path) as server:
        ensure_demo_accounts(server.app)
        seed_demo_course(server.app)
        port = urlsplit(server.url).port
        assert port is not None
        lms, seeded = start_demo_lms(server.app, "127.0.0.1", port)
        assert lms is not None and seeded == [f"the demo LMS registered as an LTI platform ({lms.url})",
                                              "its course linked to the demo course"]
        try:
            yield server, lms.url
        finally:
            lms.stop()


def test_a_person_walks_the_lti_journey_on_the_demo_lms(page, demo: tuple[LiveServer, str]) -> None:
    _server, lms_url = demo
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.goto(lms_url)
    assert "not a real LMS" in page.locator("#stand-in").text_content()
    page.screenshot(path=str(ARTIFACTS_DIR / "demo-lms-course.png"))

    # The learner opens Telelab from the course page and reaches lab-1's console inside the frame.
    page.get_by_role("link", name="Open Telelab as Lea (learner)").click()
    frame = page.frame_locator("#tool")
    frame.locator('a.robot-card[data-robot="lab-1"]').click(timeout=30000)
    frame.locator('#console[data-robot="lab-1"]').wait_for(timeout=30000)
    frame.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30000)
    page.screenshot(path=str(ARTIFACTS_DIR / "demo-lms-learner-console.png"))

    # The instructor places the demo course's practice quiz in the LMS course.
    page.goto(lms_url)
    page.get_by_role("link", name="Add Telelab content (as Ian, the instructor)").click()
    frame = page.frame_locator("#tool")
    frame.get_by_label(QUIZ).check(timeout=30000)
    page.screenshot(path=str(ARTIFACTS_DIR / "demo-lms-deep-link-picker.png"))
    frame.get_by_role("button", name="Place in the LMS course").click()
    frame.locator("#placed").wait_for(timeout=30000)
    frame.get_by_role("link", name="Back to the course").click()
    page.locator("#activities", has_text=QUIZ).wait_for(timeout=15000)

    # The learner takes it; the gradebook shows the grade Telelab sent.
    page.locator("#activities tr", has_text=QUIZ).get_by_role("link", name="Open as Lea (learner)").click()
    frame = page.frame_locator("#tool")
    frame.get_by_role("button", name="Start").click(timeout=30000)
    frame.get_by_label("Value").fill("16")  # how many sonars: the one question Lea answers
    frame.get_by_label("Value").press("Tab")
    frame.locator("#save-status", has_text="Answer saved.").wait_for(state="attached", timeout=30000)
    frame.get_by_role("button", name="Submit").click()
    frame.get_by_text("press Submit again to hand in as it is").wait_for()  # the others left blank, as she chose
    frame.get_by_role("button", name="Submit").click()
    frame.locator("#score").wait_for(timeout=30000)

    def graded() -> bool:
        page.goto(f"{lms_url}/gradebook")
        return page.locator(f'#gradebook td[data-grade="{QUIZ}"]').count() > 0

    wait_for(graded, 60, "the quiz's grade never reached the demo LMS's gradebook")
    cell = page.locator("#gradebook tr", has_text="Lea Learner").locator(f'td[data-grade="{QUIZ}"]')
    assert re.match(r"^\d+(\.\d+)? / \d+", cell.text_content() or ""), cell.text_content()
    page.screenshot(path=str(ARTIFACTS_DIR / "demo-lms-gradebook.png"))

    # On a phone, the LMS launching in Spanish: Telelab opens in Spanish inside the frame (the launch's locale).
    page.set_viewport_size({"width": 390, "height": 844})
    assert page.evaluate("document.documentElement.scrollWidth <= window.innerWidth")  # the gradebook
    page.goto(lms_url)
    page.get_by_role("link", name="Español").click()
    page.get_by_role("link", name="Open Telelab as Lea (learner)").click()
    frame = page.frame_locator("#tool")
    frame.locator('html[lang="es"] a.robot-card[data-robot="lab-1"]').wait_for(timeout=30000)
    assert page.evaluate("document.documentElement.scrollWidth <= window.innerWidth")
    page.screenshot(path=str(ARTIFACTS_DIR / "demo-lms-learner-spanish-phone.png"))
