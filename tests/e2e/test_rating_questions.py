"""A tutor writes a rating question (1-5, labelled ends) in the bank editor; a student rates it by keyboard in a quiz
on a phone and reads the rating back, unmarked. Screenshots: rating-take-phone.png, rating-result-desktop.png."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_courses_and_invitations import log_in
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e


def _quiz_of(app, course_id: int, tutor_id: int, prompt: str) -> int:
    from sqlalchemy import select

    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.assessment import Question

    with session_factory(app)() as session:
        question = session.scalars(select(Question).where(Question.prompt == prompt)).one()
        assert question.spec == {"low_label": "Not at all", "high_label": "A great deal"}
        exam = bank.create_exam(session, session.get(User, tutor_id), course_id, parse_exam(
            {"title": "After the lesson", "kind": "quiz", "question_ids": [question.id]}))
        session.commit()
        return exam.id


def test_tutor_writes_a_rating_and_a_student_rates_it_by_keyboard(chromium, page, app, live_server: LiveServer,
                                                                  course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    prompt = "The robot's sound at part 3 helped me <learn>"
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/courses/{course_people['course']}/assessment")
    adding = page.locator("#question-form")
    adding.get_by_label("Kind").select_option("rating")
    assert not adding.get_by_label("Value (numeric)").is_visible()
    adding.get_by_label("Question", exact=True).fill(prompt)
    adding.get_by_label("What 1 means (rating)").fill("Not at all")
    adding.get_by_label("What 5 means (rating)").fill("A great deal")
    adding.get_by_role("button", name="Add to the bank").click()
    page.locator(".flash--success", has_text="Question added to the bank.").wait_for()
    exam_id = _quiz_of(app, course_people["course"], course_people["tutor1"], prompt)
    page.context.clear_cookies()

    page.set_viewport_size({"width": 390, "height": 844})
    log_in(page, live_server, "student1")
    page.goto(f"{live_server.url}/assessment/exams/{exam_id}")
    page.get_by_role("button", name="Start").click()
    group = page.get_by_role("radiogroup", name="Rating from 1 (Not at all) to 5 (A great deal)")
    group.wait_for()
    assert page.get_by_text(prompt).is_visible()
    assert "a rating, not marked" in page.locator("fieldset.question legend").text_content()
    group.get_by_label("1 Not at all").focus()
    page.keyboard.press("ArrowRight")
    page.keyboard.press("ArrowRight")
    page.keyboard.press("ArrowRight")
    assert group.get_by_label("4").is_checked()
    expect(page.locator("#save-status")).to_have_text("Answer saved.")
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "rating-take-phone.png"), full_page=True)
    page.get_by_role("button", name="Submit").click()
    page.locator("#score").wait_for()
    assert page.locator("[data-result]").text_content().strip() == "Rated 4 of 5 (not marked)."
    assert "0 / 0" in " ".join(page.locator("#score").text_content().split())
    page.set_viewport_size({"width": 1280, "height": 800})
    page.screenshot(path=str(ARTIFACTS_DIR / "rating-result-desktop.png"), full_page=True)
