"""A student takes a timed test in Chromium (answers saved as they go, the server's countdown, auto-submission at
the deadline); the tutor overrides a mark with a reason and the student sees it. Screenshots at 1280x800 and 390x844.
"""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_courses_and_invitations import log_in
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e


def _make_test(app, course_people, duration_s: int) -> int:  # type: ignore[no-untyped-def]  # noqa: F811
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam, parse_question
    from middleware.db import session_factory
    from middleware.models import User

    with session_factory(app)() as session:
        tutor = session.get(User, course_people["tutor1"])
        course_id = course_people["course"]
        q1 = bank.add_question(session, tutor, course_id, parse_question(
            {"kind": "single", "prompt": "Does odometry drift?", "choices": ["No", "Yes"], "correct": 1,
             "topics": ["odometry"]}))
        q2 = bank.add_question(session, tutor, course_id, parse_question(
            {"kind": "numeric", "prompt": "Max laser range of lab-1?", "value": 5, "tolerance": 0.5, "unit": "m",
             "topics": ["sensors"]}))
        now = datetime.now(UTC)
        exam = bank.create_exam(session, tutor, course_id, parse_exam({
            "title": "Sensors <midterm>", "kind": "theory", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": duration_s,
            "question_ids": [q1.id, q2.id]}))
        session.commit()
        return exam.id


def test_student_takes_a_timed_test_and_tutor_overrides_a_mark(chromium, page, app, live_server: LiveServer,  # type: ignore[no-untyped-def]
                                                               course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    exam_id = _make_test(app, course_people, duration_s=12)
    log_in(page, live_server, "student1")
    page.get_by_role("link", name="Tests").click()
    page.get_by_role("link", name="Sensors <midterm>").click()
    page.get_by_role("button", name="Start").click()
    page.locator("#time-left").wait_for()
    page.get_by_label("Yes").check()
    page.locator("#save-status", has_text="Answer saved.").wait_for(state="attached")
    page.get_by_label("Value").fill("5.7")
    page.get_by_label("Unit").fill("m")
    page.get_by_label("Unit").press("Tab")
    page.wait_for_function("document.getElementById('save-status').textContent === 'Answer saved.'")
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-take-desktop.png"), full_page=True)
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-take-phone.png"), full_page=True)
    # No submit click: the server's deadline submits the attempt as it stands, and the page follows.
    page.locator("#score").wait_for(timeout=30000)
    assert "at the deadline" in page.locator("#score").text_content()
    assert page.locator('[data-result]').count() == 2
    attempt_url = page.url
    page.set_viewport_size({"width": 1280, "height": 800})

    tutor = chromium.new_context(viewport={"width": 1280, "height": 800}).new_page()
    log_in(tutor, live_server, "tutor1")
    tutor.goto(f"{live_server.url}/assessment/exams/{exam_id}")
    tutor.get_by_role("link", name="Review").click()
    tutor.get_by_label("Item").select_option(index=1)
    tutor.get_by_label("New mark").fill("0.5")
    tutor.get_by_label("Reason (the student sees it)").fill("Measured range accepted <partly>")
    tutor.get_by_role("button", name="Change the mark").click()
    tutor.locator(".flash--success", has_text="Mark changed.").wait_for()
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-review-desktop.png"), full_page=True)
    tutor.context.close()

    page.goto(attempt_url)
    assert "Measured range accepted <partly>" in page.locator("#comments").text_content()
    assert page.locator("#score strong").text_content() == "1.5"
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-corrected-phone.png"), full_page=True)


def test_student_answers_the_survey_and_the_tutor_sees_the_chart(chromium, page, app, live_server: LiveServer,  # type: ignore[no-untyped-def]
                                                                 course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    _make_test(app, course_people, duration_s=600)
    log_in(page, live_server, "student1")
    page.get_by_role("link", name="Tests").click()
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-hub-desktop.png"), full_page=True)
    page.get_by_role("link", name="Evaluate the lab (7 questions)").click()
    for index, group in enumerate(page.locator("fieldset.likert").all()):
        group.get_by_label("Strongly agree" if index % 2 else "Agree", exact=True).check()
    page.get_by_label("Comments (optional)").fill("<b>Great</b> lab")
    page.get_by_role("button", name="Send").click()
    page.locator(".flash--success").wait_for()

    tutor = chromium.new_context(viewport={"width": 1280, "height": 800}).new_page()
    log_in(tutor, live_server, "tutor1")
    tutor.goto(f"{live_server.url}/courses/{course_people['course']}/assessment")
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-desktop.png"), full_page=True)
    tutor.get_by_role("link", name="Survey results").first.click()
    assert tutor.locator("#survey-chart rect").count() == 7
    assert "<b>Great</b> lab" in tutor.locator("#survey-comments").text_content()
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-survey-desktop.png"), full_page=True)
    tutor.set_viewport_size({"width": 390, "height": 844})
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-survey-phone.png"), full_page=True)
    tutor.goto(f"{live_server.url}/courses/{course_people['course']}/assessment")
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone.png"), full_page=True)
    tutor.context.close()


def test_tutor_edits_a_question_and_the_course_page_fits_a_phone(chromium, page, app,  # type: ignore[no-untyped-def]
                                                                 live_server: LiveServer, course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    _make_test(app, course_people, duration_s=600)
    page.set_viewport_size({"width": 390, "height": 844})
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/courses/{course_people['course']}/assessment")
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.get_by_text("New test or quiz").click()
    page.get_by_label("Kind", exact=True).first.select_option("experimental")
    page.get_by_label("Task", exact=True).select_option("wall_following")
    assert page.get_by_label("Distance to keep (m, 0.05 to 5)").is_visible()
    assert not page.get_by_label("Target x (m)").is_visible()
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone-editor.png"), full_page=True)
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.get_by_role("link", name="Edit question #2").click()
    page.get_by_label("Question", exact=True).fill("Max laser range of lab-1, in metres?")
    page.get_by_label("Tolerance ± (numeric)").fill("0.25")
    page.get_by_role("button", name="Save the question").click()
    page.locator(".flash--success", has_text="Question #2 saved.").wait_for()
    assert "Max laser range of lab-1, in metres?" in page.locator("#questions").text_content()
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone-edited.png"), full_page=True)
