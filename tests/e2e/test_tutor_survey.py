"""A tutor writes the course's survey in the editor (an empty one is refused under the field), a student answers it
by keyboard on a phone, and the tutor reads the chart with each statement's ends. Screenshots: survey-edit-desktop,
survey-answer-phone, survey-written-results-desktop (.png)."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_courses_and_invitations import log_in
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e
STATEMENTS = ("Part 1 (the robot drives slowly) helped me learn\n"
              "Part 3 (the robot's <sound>) helped me learn | Not at all | A great deal")


def _two_more_answer(app, course_id: int, student2_id: int) -> None:
    from middleware.assessment import survey
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import CourseMembership, User
    from tests.conftest import STUDENT_PASSWORD

    with session_factory(app)() as session:
        third = create_user(session, "student3", "student", STUDENT_PASSWORD)
        session.add(CourseMembership(course_id=course_id, user_id=third.id, role="student"))
        session.flush()
        for student in (session.get(User, student2_id), third):
            survey.submit_survey(session, student, course_id, {"s1": 3, "s2": 5}, "")
        session.commit()


def test_tutor_writes_the_survey_and_a_student_answers_it_by_keyboard(chromium, page, app, live_server: LiveServer,
                                                                      course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    course = course_people["course"]
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/courses/{course}/assessment")
    page.get_by_role("link", name="Write the survey").click()
    assert "seven standard statements" in page.locator(".page-heading").text_content()
    page.get_by_label("Title students read").fill("After the ROS lesson")
    page.get_by_label("Statements, one per line").fill("   ")
    page.get_by_role("button", name="Save the survey").click()
    assert "at least one statement" in page.locator("#e-statements").text_content()
    page.get_by_label("Statements, one per line").fill(STATEMENTS)
    page.get_by_role("button", name="Save the survey").click()
    page.locator(".flash--success", has_text="The survey is saved").wait_for()
    assert page.get_by_label("Statements, one per line").input_value().splitlines()[1] == \
        "Part 3 (the robot's <sound>) helped me learn | Not at all | A great deal"
    page.screenshot(path=str(ARTIFACTS_DIR / "survey-edit-desktop.png"), full_page=True)
    page.context.clear_cookies()

    page.set_viewport_size({"width": 390, "height": 844})
    log_in(page, live_server, "student1")
    page.goto(f"{live_server.url}/assessment")
    page.get_by_role("link", name="After the ROS lesson (2 questions)").click()
    page.get_by_role("radio", name="Agree", exact=True).first.focus()  # part 1: the agreement scale
    page.keyboard.press("Space")
    page.keyboard.press("Tab")  # into part 3's group
    page.keyboard.press("ArrowLeft")  # from the first radio, wraps to the last: 5
    assert page.locator('[data-statement="s2"]').get_by_label("5 (A great deal)").is_checked()
    assert page.locator('[data-statement="s1"]').get_by_label("Agree", exact=True).is_checked()
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "survey-answer-phone.png"), full_page=True)
    page.get_by_role("button", name="Send").click()
    page.locator(".flash--success", has_text="your answers were recorded").wait_for()
    page.context.clear_cookies()

    _two_more_answer(app, course, course_people["student2"])
    page.set_viewport_size({"width": 1280, "height": 800})
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/courses/{course}/survey/results")
    row = page.locator('#survey-table [data-item="s2"]')
    assert "(1 = Not at all, 5 = A great deal)" in row.text_content()
    assert [c.text_content() for c in row.locator("td").all()] == ["0", "0", "0", "0", "3"]
    page.screenshot(path=str(ARTIFACTS_DIR / "survey-written-results-desktop.png"), full_page=True)
    page.goto(f"{live_server.url}/courses/{course}/survey/edit")
    assert "3 students have answered" in page.locator("#survey-fixed").text_content()
    assert page.get_by_role("button", name="Save the survey").is_disabled()
