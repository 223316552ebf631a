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


def _make_test(app, course_people, duration_s: int, numeric_first: bool = False) -> int:  # noqa: F811
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
            "question_ids": [q2.id, q1.id] if numeric_first else [q1.id, q2.id]}))
        session.commit()
        return exam.id


def test_student_takes_a_timed_test_and_tutor_overrides_a_mark(chromium, page, app, live_server: LiveServer,
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


def test_an_answer_typed_before_the_page_script_ran_is_saved(
        page, app, live_server: LiveServer, course_people) -> None:  # noqa: F811
    """On a slow load a student types before the page's module listens for changes: the answer is saved all the same
    (the clean-clone suite, loaded, once waited 30 s for an 'Answer saved.' that never came)."""
    exam_id = _make_test(app, course_people, duration_s=600, numeric_first=True)
    log_in(page, live_server, "student1")
    page.goto(f"{live_server.url}/assessment/exams/{exam_id}")
    held = []
    page.route("**/pages/assessment/assessment-take.js", lambda route: held.append(route))  # held until typed
    page.get_by_role("button", name="Start").click()
    page.get_by_label("Value").fill("5")
    page.get_by_label("Value").press("Tab")
    assert held, "the page asked for its script"
    held[0].continue_()
    page.unroute("**/pages/assessment/assessment-take.js")
    page.locator("#save-status", has_text="Answer saved.").wait_for(state="attached")
    page.reload()
    assert page.get_by_label("Value").input_value() == "5"


def test_unit_is_filled_in_unanswered_questions_are_named_and_the_corrector_counts_as_the_student(
        chromium, page, app, live_server: LiveServer, course_people) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    exam_id = _make_test(app, course_people, duration_s=600, numeric_first=True)
    page.set_viewport_size({"width": 390, "height": 844})
    log_in(page, live_server, "student1")
    page.goto(f"{live_server.url}/assessment/exams/{exam_id}")
    page.get_by_role("button", name="Start").click()
    assert page.get_by_label("Unit").input_value() == "m"
    page.get_by_label("Value").fill("5")
    page.get_by_label("Value").press("Tab")
    page.locator("#save-status", has_text="Answer saved.").wait_for(state="attached")
    page.get_by_role("button", name="Submit").scroll_into_view_if_needed()
    box = page.locator("#countdown").bounding_box()
    assert box is not None and 0 <= box["y"] < 844 and "Time left" in page.locator("#countdown").text_content()
    page.get_by_role("button", name="Submit").click()
    warning = page.get_by_role("alert")
    assert warning.text_content().startswith("1 question is not answered: Question 2.")
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-unanswered-phone.png"))
    page.get_by_role("button", name="Submit").click()
    page.locator("#score").wait_for()
    assert page.locator("#score strong").text_content() == "1"
    attempt_url = page.url

    tutor = chromium.new_context(viewport={"width": 1280, "height": 800}).new_page()
    log_in(tutor, live_server, "tutor1")
    tutor.goto(attempt_url)
    legends = [text.split("(")[0].strip() for text in tutor.locator("legend").all_text_contents()]
    assert legends == ["Question 1", "Question 2"]
    options = tutor.get_by_label("Item").locator("option").all_text_contents()
    assert options == ["Question 1 (1/1)", "Question 2 (0/1)"]
    tutor.get_by_label("Item").select_option(label="Question 2 (0/1)")
    tutor.get_by_label("New mark").fill("1")
    tutor.get_by_label("Reason (the student sees it)").fill("Left blank by a page fault")
    tutor.get_by_role("button", name="Change the mark").click()
    tutor.locator(".flash--success", has_text="Mark changed.").wait_for()
    assert "on question 2" in tutor.locator("#comments").text_content()
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-override-desktop.png"), full_page=True)
    tutor.context.close()

    page.goto(attempt_url)
    changed = page.locator("fieldset", has_text="Question 2").locator("[data-result]")
    assert changed.locator("p").first.text_content() == "1/1 set by the tutor: Left blank by a page fault"
    assert "Replaces the automatic mark 0: No answer." in changed.text_content()
    assert "result--wrong" not in changed.get_attribute("class")
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-overridden-phone.png"), full_page=True)


def _two_more_answer_the_survey(app, course_people) -> None:  # noqa: F811
    from middleware.assessment import survey
    from middleware.assessment.schemas import SURVEY_ITEMS
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import CourseMembership, User
    from tests.conftest import STUDENT_PASSWORD

    with session_factory(app)() as session:
        third = create_user(session, "student3", "student", STUDENT_PASSWORD)
        session.add(CourseMembership(course_id=course_people["course"], user_id=third.id, role="student"))
        session.flush()
        ratings = {key: 3 for key, _label in SURVEY_ITEMS}
        for student in (session.get(User, course_people["student2"]), third):
            survey.submit_survey(session, student, course_people["course"], ratings, "")
        session.commit()


def test_student_answers_the_survey_and_the_tutor_sees_the_chart(chromium, page, app, live_server: LiveServer,
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
    assert tutor.locator("#respondents").text_content() == "1 person has answered."
    assert "at least 3 students" in tutor.locator("#survey-hidden").text_content()
    assert tutor.locator("#survey-chart").count() == 0 and tutor.locator("#survey-comments").count() == 0
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-survey-hidden-desktop.png"), full_page=True)
    _two_more_answer_the_survey(app, course_people)
    tutor.reload()
    assert tutor.locator("#respondents").text_content() == "3 people have answered."
    assert tutor.locator("#survey-chart rect").count() == 14  # per question: student1's answer, and two neutral
    assert "<b>Great</b> lab" in tutor.locator("#survey-comments").text_content()
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-survey-desktop.png"), full_page=True)
    tutor.set_viewport_size({"width": 390, "height": 844})
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-survey-phone.png"), full_page=True)
    tutor.goto(f"{live_server.url}/courses/{course_people['course']}/assessment")
    tutor.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone.png"), full_page=True)
    tutor.context.close()


def test_tutor_edits_a_question_and_the_course_page_fits_a_phone(chromium, page, app,
                                                                 live_server: LiveServer, course_people) -> None:  # noqa: F811
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models.assessment import Question

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
    assert page.locator("#rubric-bound-0").input_value() == "0.1"
    assert page.locator("#rubric-share-0").input_value() == "100"
    assert page.get_by_label("earns (% of the points)").count() == 5
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone-editor.png"), full_page=True)
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    adding = page.locator("#question-form")
    adding.get_by_label("Kind").select_option("numeric")
    assert adding.get_by_label("Value (numeric)").is_visible()
    assert not adding.get_by_label("Choices, one per line (choice questions)").is_visible()
    adding.get_by_label("Kind").select_option("single")
    assert not adding.get_by_label("Value (numeric)").is_visible()
    adding.get_by_label("Question", exact=True).fill("Which sensor measures distance?")
    adding.get_by_label("Choices, one per line (choice questions)").fill("Camera\nSonar")
    adding.get_by_label("Right choice numbers, 1 for the first line, comma-separated (choice questions)").fill("2")
    adding.get_by_role("button", name="Add to the bank").click()
    page.locator(".flash--success", has_text="Question added to the bank.").wait_for()
    with session_factory(app)() as session:
        added = session.scalars(select(Question).where(Question.prompt == "Which sensor measures distance?")).one()
        assert added.spec["correct"] == 1  # the second line
    page.get_by_role("link", name="Edit question #2").click()
    page.get_by_label("Question", exact=True).fill("Max laser range of lab-1, in metres?")
    page.get_by_label("Tolerance ± (numeric)").fill("0.25")
    page.get_by_role("button", name="Save the question").click()
    page.locator(".flash--success", has_text="Question #2 saved.").wait_for()
    assert "Max laser range of lab-1, in metres?" in page.locator("#questions").text_content()
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "assessment-course-phone-edited.png"), full_page=True)


def test_tutor_enrols_with_a_typo_and_reaches_tests_grades_and_survey_from_the_course_page(
        chromium, page, app, live_server: LiveServer, course_people) -> None:  # noqa: F811
    from middleware.assessment import attempts
    from middleware.db import session_factory
    from middleware.models import User

    ARTIFACTS_DIR.mkdir(exist_ok=True)
    exam_id = _make_test(app, course_people, duration_s=600)
    with session_factory(app)() as session:
        student = session.get(User, course_people["student1"])
        attempt = attempts.start_attempt(session, student, exam_id, datetime.now(UTC))
        attempts.submit_attempt(session, student, attempt.id, datetime.now(UTC), {"1": 1})
        session.commit()
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/courses/{course_people['course']}")
    page.get_by_label("Username of an existing student").fill("studnet2")
    page.get_by_role("button", name="Enrol", exact=True).click()
    error = page.locator('[data-error-for="username"]')
    assert "There is no account named 'studnet2'" in error.text_content()
    assert page.get_by_label("Username of an existing student").input_value() == "studnet2"
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-enrol-typo-desktop.png"), full_page=True)

    page.get_by_role("link", name="Tests and question bank").click()
    page.locator("h1", has_text="ROB1 · assessment").wait_for()
    page.go_back()
    page.get_by_role("link", name="Survey results").click()
    page.locator("h1", has_text="System evaluation").wait_for()
    page.go_back()
    page.get_by_role("link", name="Gradebook").click()
    table = page.locator("#gradebook")
    assert "Sensors <midterm>" in table.locator("thead").text_content()
    assert table.locator('[data-student="student1"] td').all_text_contents() == ["1"]
    assert table.locator('[data-student="student2"] td').all_text_contents() == ["—"]
    page.screenshot(path=str(ARTIFACTS_DIR / "gradebook-desktop.png"), full_page=True)
    page.set_viewport_size({"width": 390, "height": 844})
    assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
    page.screenshot(path=str(ARTIFACTS_DIR / "gradebook-phone.png"), full_page=True)
    page.goto(f"{live_server.url}/courses/{course_people['course']}")
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-detail-phone.png"), full_page=True)
