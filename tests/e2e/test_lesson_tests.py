"""A lesson with a test before and after, in Chromium: the student finds the video held back until the test before
is submitted, takes the test after, and reads the comparison per part; the tutor reads the class's. Screenshots:
lesson-blocked-phone.png, lesson-results-phone.png, lesson-results-tutor-desktop.png."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_courses_and_invitations import log_in
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e


def _lesson_with_tests(app, course_people) -> tuple[int, str]:  # noqa: F811
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam, parse_question
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.teaching import Lesson

    with session_factory(app)() as session:
        tutor, course = session.get(User, course_people["tutor1"]), course_people["course"]
        drive = bank.add_question(session, tutor, course, parse_question(
            {"kind": "single", "prompt": "0.2 m/s and 0 rad/s makes the robot…", "choices": ["Turn", "Go ahead"],
             "correct": 1, "topics": ["part 1: forward"]}))
        rating = bank.add_question(session, tutor, course, parse_question(
            {"kind": "rating", "prompt": "Part 1 (the robot drove with the video) helped me learn",
             "topics": ["part 1: forward"]}))
        before = bank.create_exam(session, tutor, course, parse_exam(
            {"title": "Before: first moves", "kind": "quiz", "question_ids": [drive.id]}))
        after = bank.create_exam(session, tutor, course, parse_exam(
            {"title": "After: first moves", "kind": "quiz", "question_ids": [drive.id, rating.id]}))
        lesson = Lesson(slug="first-moves", title="First moves", video_name="none.webm", cues_vtt="WEBVTT\n",
                        before_exam_id=before.id, after_exam_id=after.id)
        session.add(lesson)
        session.commit()
        return lesson.id, "0.2 m/s and 0 rad/s makes the robot…"


def _take(page, live_server: LiveServer, title: str, choice: str, rating: str | None = None) -> None:
    page.get_by_role("link", name=title).click()
    page.get_by_role("button", name="Start").click()
    page.get_by_label(choice).check()
    if rating:
        page.get_by_role("radiogroup").get_by_label(rating).check()
    expect(page.locator("#save-status")).to_have_text("Answer saved.")
    page.get_by_role("button", name="Submit").click()
    page.locator("#score").wait_for()


def test_the_lesson_waits_for_the_test_before_and_compares_the_parts(chromium, page, app, live_server: LiveServer,
                                                                     course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    lesson_id, _prompt = _lesson_with_tests(app, course_people)
    page.set_viewport_size({"width": 390, "height": 844})
    log_in(page, live_server, "student1")
    page.goto(f"{live_server.url}/lessons/{lesson_id}")
    assert "submitted “Before: first moves”" in page.get_by_test_id("lesson-blocked").text_content()
    assert page.get_by_test_id("lesson-video").count() == 0
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "lesson-blocked-phone.png"), full_page=True)
    _take(page, live_server, "Before: first moves", "Turn")  # wrong before the video
    page.goto(f"{live_server.url}/lessons/{lesson_id}")
    assert page.get_by_test_id("lesson-video").count() == 1
    assert page.locator('[data-field="before-state"]').text_content() == "done"
    _take(page, live_server, "After: first moves", "Go ahead", rating="5")
    page.goto(f"{live_server.url}/lessons/{lesson_id}")
    page.get_by_role("link", name="Compare before and after, part by part").click()
    row = page.locator('#lesson-parts [data-part="part 1: forward"]')
    assert [c.text_content() for c in row.locator("td").all()] == ["0 %", "100 %", "+100 points", "5.0"]
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "lesson-results-phone.png"), full_page=True)
    page.context.clear_cookies()

    page.set_viewport_size({"width": 1280, "height": 800})
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/lessons/{lesson_id}/results")
    assert page.locator('[data-field="whose"]').text_content().startswith("1 student has taken both tests")
    page.screenshot(path=str(ARTIFACTS_DIR / "lesson-results-tutor-desktop.png"), full_page=True)
